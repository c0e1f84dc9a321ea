//! The built-in scenes of SPEC §4, exactly as specified.
//!
//! Frame: robot base at the origin on the platform top, x along the channel,
//! y left, z up, metres.

use crate::material::default_materials;
use crate::primitives::Axis;
use crate::spec::{ObjectSpec, SceneSpec, ShapeSpec};
use geom::Real;

/// Names of the built-in scenes.
pub const NAMES: [&str; 7] = [
    "bridge1", "bridge2", "bridge3", "cube", "block1", "block2", "cylinder",
];

fn object(name: &str, material: &str, shape: ShapeSpec) -> ObjectSpec {
    ObjectSpec {
        name: name.to_owned(),
        material: material.to_owned(),
        pose: None,
        shape,
    }
}

fn boxed(name: &str, material: &str, min: [Real; 3], max: [Real; 3]) -> ObjectSpec {
    object(name, material, ShapeSpec::Box { min, max })
}

fn i_beam(name: &str, y: Real) -> ObjectSpec {
    // Flanges 0.30 × 0.02, web 0.012 thick centred on y, from z 0.80 to 1.52:
    // bottom flange [0.80, 0.82], web [0.82, 1.50], top flange [1.50, 1.52].
    object(
        name,
        "painted_metal",
        ShapeSpec::IBeam {
            from: [-2.0, y, 0.80],
            to: [2.0, y, 0.80],
            up: [0.0, 0.0, 1.0],
            depth: 0.72,
            flange_width: 0.30,
            flange_thickness: 0.02,
            web_thickness: 0.012,
        },
    )
}

fn tube(name: &str, material: &str, from: [Real; 3], to: [Real; 3], radius: Real) -> ObjectSpec {
    object(
        name,
        material,
        ShapeSpec::Cylinder {
            from,
            to,
            radius,
            segments: 32,
        },
    )
}

/// bridge1 (A§6.3, the "simple" environment).
fn bridge1() -> Vec<ObjectSpec> {
    vec![
        boxed(
            "platform",
            "painted_metal",
            [-0.6, -0.5, -0.05],
            [0.6, 0.5, 0.0],
        ),
        boxed("floor", "concrete", [-2.0, -1.0, -0.10], [2.0, 1.0, -0.05]),
        i_beam("left_beam", 0.75),
        i_beam("right_beam", -0.75),
        boxed("roof", "timber", [-2.0, -1.0, 1.52], [2.0, 1.0, 1.60]),
        boxed(
            "plate",
            "painted_metal",
            [-0.4, 0.738, 0.95],
            [0.4, 0.744, 1.35],
        ),
        boxed(
            "sheet",
            "plastic",
            [-1.5, -0.744, 0.82],
            [1.5, -0.740, 1.50],
        ),
        tube(
            "scaffold_left",
            "painted_metal",
            [0.45, 0.55, -0.05],
            [0.45, 0.55, 0.80],
            0.025,
        ),
        tube(
            "scaffold_right",
            "painted_metal",
            [0.45, -0.55, -0.05],
            [0.45, -0.55, 0.80],
            0.025,
        ),
        tube(
            "blast_hose",
            "plastic",
            [-0.6, 0.35, 0.03],
            [0.6, 0.35, 0.03],
            0.03,
        ),
    ]
}

/// bridge2 (A§6.4): bridge1 plus a timber crossbeam directly behind the robot.
fn bridge2() -> Vec<ObjectSpec> {
    let mut v = bridge1();
    v.push(boxed(
        "crossbeam_back",
        "timber",
        [-0.72, -0.744, 1.20],
        [-0.58, 0.744, 1.50],
    ));
    v
}

/// bridge3 (A§6.5): bridge2 plus a mirrored crossbeam in front and a timber
/// lattice hanging from the back crossbeam.
fn bridge3() -> Vec<ObjectSpec> {
    let mut v = bridge2();
    v.push(boxed(
        "crossbeam_front",
        "timber",
        [0.58, -0.744, 1.20],
        [0.72, 0.744, 1.50],
    ));
    for k in 0..7 {
        let y = -0.6 + 0.2 * Real::from(k);
        v.push(boxed(
            &format!("lattice_vertical_{k}"),
            "timber",
            [-0.60, y - 0.02, 0.90],
            [-0.58, y + 0.02, 1.20],
        ));
    }
    for (k, z) in [0.95, 1.10].into_iter().enumerate() {
        v.push(boxed(
            &format!("lattice_horizontal_{k}"),
            "timber",
            [-0.60, -0.62, z - 0.02],
            [-0.58, 0.62, z + 0.02],
        ));
    }
    v
}

fn prism_y(name: &str, profile: &[[Real; 2]], y0: Real, y1: Real) -> ObjectSpec {
    object(
        name,
        "painted_metal",
        ShapeSpec::Prism {
            axis: Axis::Y,
            profile: profile.to_vec(),
            from: y0,
            to: y1,
        },
    )
}

/// The scene of a built-in by name, or `None` for an unknown name.
pub fn scene(name: &str) -> Option<SceneSpec> {
    let objects = match name {
        "bridge1" => bridge1(),
        "bridge2" => bridge2(),
        "bridge3" => bridge3(),
        "cube" => vec![boxed(
            "cube",
            "painted_metal",
            [-0.5, -0.5, 0.0],
            [0.5, 0.5, 1.0],
        )],
        "block1" => vec![prism_y(
            "block1",
            &[
                [-0.6, 0.0],
                [0.6, 0.0],
                [0.6, 0.4],
                [0.0, 0.4],
                [0.0, 0.8],
                [-0.6, 0.8],
            ],
            -0.35,
            0.35,
        )],
        "block2" => vec![prism_y(
            "block2",
            // Box [-0.5,0.5]×[0,0.6] in (x, z) with the top edges chamfered by the
            // planes through (0.5, 0.3)–(0.2, 0.6) and (-0.5, 0.4)–(-0.15, 0.6).
            &[
                [-0.5, 0.0],
                [0.5, 0.0],
                [0.5, 0.3],
                [0.2, 0.6],
                [-0.15, 0.6],
                [-0.5, 0.4],
            ],
            -0.4,
            0.4,
        )],
        "cylinder" => vec![object(
            "cylinder",
            "painted_metal",
            ShapeSpec::Cylinder {
                from: [0.0, 0.0, 0.0],
                to: [0.0, 0.0, 0.8],
                radius: 0.4,
                segments: 128,
            },
        )],
        _ => return None,
    };
    Some(SceneSpec {
        materials: default_materials(),
        objects,
        point_cloud: None,
    })
}
