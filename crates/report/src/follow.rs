//! The report of a `surveyor follow` run (Pudney ch. 4): the surface model's
//! polygons with their shared edges and corner vertices, the control-point
//! path over the completed model (Figs 45 and 47), the model's evolution at
//! chosen numbers of sensor sets (Figs 44 and 46), and per step the motion
//! mode, the step times and what the sensors saw.

use crate::ReportError;
use crate::explore::truth_meshes;
use crate::geometry::{Polylines, columns, plane_basis, triangulate};
use crate::page::{Page, plot_of, xy_layout};
use geom::{Point3, Real, Vector3};
use plotly::common::{Line, LineShape, Marker, MarkerSymbol, Mode, Title, Visible};
use plotly::layout::{
    AspectMode, AspectRatio, Axis, AxisType, Camera, CategoryOrder, LayoutScene, Legend, Margin,
};
use plotly::{Layout, Mesh3D, Scatter, Scatter3D, Trace};
use record::{RunFolder, StepRow};
use std::path::Path;
use surface::{ModelJson, SegmentJson};

/// The motion modes of P§3.4 in the order the thesis gives them.
pub const MODES: [&str; 5] = ["surface", "segment", "edge", "point", "gap"];

/// Colours of the polygon segments (cycled in id order).
const SEGMENT_COLOURS: [&str; 10] = [
    "#4e79a7", "#f28e2b", "#59a14f", "#b07aa1", "#edc948", "#76b7b2", "#ff9da7", "#9c755f",
    "#86bcb6", "#bab0ac",
];
/// Colour of shared edges.
const SHARED_COLOUR: &str = "#d62728";
/// Colour of corner vertices.
const CORNER_COLOUR: &str = "#000000";
/// Colour of the control-point path.
const PATH_COLOUR: &str = "#1f3f9f";

/// One edge of a polygon segment that is shared with a neighbour.
#[derive(Clone, Debug, PartialEq)]
pub struct SharedEdge {
    /// The segment whose perimeter holds the edge.
    pub segment: u32,
    /// The neighbour it is shared with.
    pub neighbour: u32,
    /// Index of the edge in the segment's perimeter.
    pub edge: usize,
    /// Where it starts and ends.
    pub ends: [Point3; 2],
}

fn point(v: &[Real; 3]) -> Point3 {
    Point3::new(v[0], v[1], v[2])
}

/// The shared edges of every polygon (each pair appears twice, once from
/// each side) and the corner vertices (one per flag: a corner modelled by
/// three segments appears three times).
pub fn shared_edges_and_corners(model: &ModelJson) -> (Vec<SharedEdge>, Vec<Point3>) {
    let mut shared = Vec::new();
    let mut corners = Vec::new();
    for s in &model.segments {
        let SegmentJson::Polygon {
            id,
            vertices,
            edges,
            ..
        } = s
        else {
            continue;
        };
        let n = vertices.len();
        for (i, e) in edges.iter().enumerate().take(n) {
            if let Some(neighbour) = e.shared_with {
                shared.push(SharedEdge {
                    segment: *id,
                    neighbour,
                    edge: i,
                    ends: [point(&vertices[i]), point(&vertices[(i + 1) % n])],
                });
            }
            if e.corner_start {
                corners.push(point(&vertices[i]));
            }
        }
    }
    (shared, corners)
}

/// A planar polygon as triangles in 3-D: its vertices projected on the plane
/// through the first vertex normal to `normal`, ear-clipped there.
pub fn polygon_triangles(vertices: &[[Real; 3]], normal: &[Real; 3]) -> Vec<[usize; 3]> {
    let n = geom::unit(Vector3::new(normal[0], normal[1], normal[2]))
        .map_or_else(Vector3::z, geom::UnitVector3::into_inner);
    let (u, v) = plane_basis(&n);
    let Some(first) = vertices.first().map(point) else {
        return Vec::new();
    };
    let flat: Vec<[Real; 2]> = vertices
        .iter()
        .map(|p| {
            let d = point(p) - first;
            [d.dot(&u), d.dot(&v)]
        })
        .collect();
    triangulate(&flat)
}

/// Which segments to draw.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Initial {
    /// The initial (a priori) segments too, hidden until clicked.
    Hidden,
    /// Leave them out (Pudney's Figs 44 and 46 do).
    Omit,
}

/// The shared edges (thick) and corner vertices (diamonds) of a model;
/// with [`Initial::Omit`], only those between non-initial segments.
fn relation_traces(model: &ModelJson, initial: Initial, legend: bool) -> Vec<Box<dyn Trace>> {
    let mut traces: Vec<Box<dyn Trace>> = Vec::new();
    let non_initial = |id: u32| {
        model.segments.iter().any(|s| match s {
            SegmentJson::Polygon {
                id: i, initial: x, ..
            } => *i == id && !*x,
            SegmentJson::Point { .. } => false,
        })
    };
    let (shared, corners) = shared_edges_and_corners(model);
    let mut shared_lines = Polylines::default();
    let mut drawn = 0usize;
    for e in &shared {
        if initial == Initial::Omit && !(non_initial(e.segment) && non_initial(e.neighbour)) {
            continue;
        }
        shared_lines.push(&e.ends);
        drawn += 1;
    }
    if !shared_lines.is_empty() {
        let [x, y, z] = shared_lines.xyz;
        traces.push(
            Scatter3D::new(x, y, z)
                .mode(Mode::Lines)
                .name(format!("shared edges ({} pairs)", drawn / 2))
                .connect_gaps(false)
                .show_legend(legend)
                .line(Line::new().color(SHARED_COLOUR).width(7.0)),
        );
    }
    if !corners.is_empty() {
        let [x, y, z] = columns(&corners);
        traces.push(
            Scatter3D::new(x, y, z)
                .mode(Mode::Markers)
                .name(format!("corner vertices ({})", corners.len()))
                .show_legend(legend)
                .marker(
                    Marker::new()
                        .size(5)
                        .symbol(MarkerSymbol::Diamond)
                        .color(CORNER_COLOUR),
                ),
        );
    }
    traces
}

/// The traces of a model: polygons (one colour per segment), their
/// outlines, shared edges, corner vertices and point segments; `legend`
/// shows their legend entries.
fn model_traces(model: &ModelJson, initial: Initial, legend: bool) -> Vec<Box<dyn Trace>> {
    let mut traces: Vec<Box<dyn Trace>> = Vec::new();
    let mut mesh: Vec<Point3> = Vec::new();
    let mut tris: Vec<[usize; 3]> = Vec::new();
    let mut face_colours: Vec<&'static str> = Vec::new();
    let mut hover: Vec<String> = Vec::new();
    let mut outlines = Polylines::default();
    let mut initial_mesh: Vec<Point3> = Vec::new();
    let mut initial_tris: Vec<[usize; 3]> = Vec::new();
    let mut points: Vec<Point3> = Vec::new();
    let mut point_hover: Vec<String> = Vec::new();
    let mut polygons = 0usize;
    for s in &model.segments {
        match s {
            SegmentJson::Point {
                id,
                points: m,
                centroid,
                ..
            } => {
                points.push(point(centroid));
                point_hover.push(format!("point segment {id}, {m} points"));
            }
            SegmentJson::Polygon {
                id,
                points: m,
                initial: is_initial,
                normal,
                vertices,
                ..
            } => {
                let local = polygon_triangles(vertices, normal);
                if *is_initial {
                    if initial == Initial::Omit {
                        continue;
                    }
                    let base = initial_mesh.len();
                    initial_mesh.extend(vertices.iter().map(point));
                    initial_tris.extend(local.iter().map(|t| t.map(|v| base + v)));
                    continue;
                }
                let colour = SEGMENT_COLOURS[polygons % SEGMENT_COLOURS.len()];
                polygons += 1;
                let base = mesh.len();
                mesh.extend(vertices.iter().map(point));
                hover.extend(vertices.iter().map(|_| format!("segment {id}, {m} points")));
                for t in &local {
                    tris.push(t.map(|v| base + v));
                    face_colours.push(colour);
                }
                let mut ring: Vec<Point3> = vertices.iter().map(point).collect();
                if let Some(first) = ring.first().copied() {
                    ring.push(first);
                }
                outlines.push(&ring);
            }
        }
    }
    let split = |t: &[[usize; 3]], c: usize| -> Vec<usize> { t.iter().map(|t| t[c]).collect() };
    if !initial_tris.is_empty() {
        let [x, y, z] = columns(&initial_mesh);
        traces.push(
            Mesh3D::new(
                x,
                y,
                z,
                Some(split(&initial_tris, 0)),
                Some(split(&initial_tris, 1)),
                Some(split(&initial_tris, 2)),
            )
            .name("initial segments")
            .color("#9e9e9e")
            .opacity(0.3)
            .show_legend(legend)
            .visible(Visible::LegendOnly),
        );
    }
    if !tris.is_empty() {
        let [x, y, z] = columns(&mesh);
        traces.push(
            Mesh3D::new(
                x,
                y,
                z,
                Some(split(&tris, 0)),
                Some(split(&tris, 1)),
                Some(split(&tris, 2)),
            )
            .name(format!("polygon segments ({polygons})"))
            .face_color(face_colours)
            .hover_text_array(hover)
            .flat_shading(true)
            .show_legend(legend),
        );
    }
    if !outlines.is_empty() {
        let [x, y, z] = outlines.xyz;
        traces.push(
            Scatter3D::new(x, y, z)
                .mode(Mode::Lines)
                .name("polygon perimeters")
                .connect_gaps(false)
                .show_legend(legend)
                .line(Line::new().color("#303030").width(2.0)),
        );
    }
    traces.extend(relation_traces(model, initial, legend));
    if !points.is_empty() {
        let [x, y, z] = columns(&points);
        traces.push(
            Scatter3D::new(x, y, z)
                .mode(Mode::Markers)
                .name(format!("point segments ({})", points.len()))
                .hover_text_array(point_hover)
                .show_legend(legend)
                .marker(Marker::new().size(3).color("#7f7f7f")),
        );
    }
    traces
}

/// An axis-aligned box around points, grown by `margin` metres.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    min: [Real; 3],
    max: [Real; 3],
}

impl Bounds {
    fn of<'a>(points: impl IntoIterator<Item = &'a Point3>, margin: Real) -> Option<Self> {
        let mut b: Option<Self> = None;
        for p in points {
            let v = [p.x, p.y, p.z];
            if v.iter().any(|x| !x.is_finite()) {
                continue;
            }
            let c = b.get_or_insert(Self { min: v, max: v });
            c.min = [0, 1, 2].map(|k| c.min[k].min(v[k]));
            c.max = [0, 1, 2].map(|k| c.max[k].max(v[k]));
        }
        b.map(|mut b| {
            for k in 0..3 {
                b.min[k] -= margin;
                b.max[k] += margin;
            }
            b
        })
    }

    /// A scene with these axis ranges, drawn to scale.
    fn scene(&self) -> LayoutScene {
        let size = [0, 1, 2].map(|k| self.max[k] - self.min[k]);
        let big = size.iter().copied().fold(1e-9, Real::max);
        let axis = |k: usize, name: &str| {
            Axis::new()
                .title(Title::with_text(name))
                .range(vec![self.min[k], self.max[k]])
        };
        LayoutScene::new()
            .aspect_mode(AspectMode::Manual)
            .aspect_ratio(AspectRatio::from((
                size[0] / big,
                size[1] / big,
                size[2] / big,
            )))
            .camera(Camera::new().eye((-1.1, -1.5, 1.0).into()))
            .x_axis(axis(0, "x (m)"))
            .y_axis(axis(1, "y (m)"))
            .z_axis(axis(2, "z (m)"))
    }
}

/// The sensed part of a model (no initial segments): vertices and points.
fn sensed_points(model: &ModelJson) -> Vec<Point3> {
    let mut out = Vec::new();
    for s in &model.segments {
        match s {
            SegmentJson::Polygon {
                initial: false,
                vertices,
                ..
            } => out.extend(vertices.iter().map(point)),
            SegmentJson::Point { centroid, .. } => out.push(point(centroid)),
            SegmentJson::Polygon { .. } => {}
        }
    }
    out
}

/// The ground truth of the run's scenario, one mesh per material (hidden
/// until clicked), when the folder has `scenario.toml` and its world is a
/// mesh scene.
fn truth_traces(folder: &RunFolder, traces: &mut Vec<Box<dyn Trace>>) -> Result<bool, ReportError> {
    let Some(loaded) = crate::scenario_of(folder)? else {
        return Ok(false);
    };
    let scene::World::Mesh(scene) = loaded.build_world()? else {
        return Ok(false);
    };
    truth_meshes(&scene, traces);
    Ok(true)
}

/// Build the page of the follow run in `folder`, naming it `shown`.
pub fn page(folder: &RunFolder, shown: &Path) -> Result<Page, ReportError> {
    let run = folder.summary_json();
    let steps = folder.steps()?;
    let model = folder.surface_model()?;
    let scenario = folder.scenario().to_owned();
    let robot = run["robot"].as_str().unwrap_or("?").to_owned();
    let mut page = Page::new(&format!("surveyor follow: {scenario}, {robot}"));
    page.intro(&format!(
        "Surface following (Pudney 1994) of {scenario} with {robot}, run folder {}.",
        shown.display()
    ));

    let path: Vec<Point3> = steps.iter().map(|r| r.control_point).collect();
    let mut framed = sensed_points(&model);
    framed.extend(path.iter().copied());
    let bounds = Bounds::of(&framed, 0.05);

    // The completed model and the path (Figs 45 and 47).
    let mut traces = Vec::new();
    let truth = truth_traces(folder, &mut traces)?;
    traces.extend(model_traces(&model, Initial::Hidden, true));
    if !path.is_empty() {
        let [x, y, z] = columns(&path);
        traces.push(
            Scatter3D::new(x, y, z)
                .mode(Mode::Lines)
                .name(format!("control-point path ({} steps)", path.len()))
                .line(Line::new().color(PATH_COLOUR).width(2.0)),
        );
        let ends = [path[0], path[path.len() - 1]];
        let [x, y, z] = columns(&ends);
        traces.push(
            Scatter3D::new(x, y, z)
                .mode(Mode::Markers)
                .name("path start (green), end (red)")
                .marker(
                    Marker::new()
                        .size(6)
                        .color_array(vec!["#2ca02c".to_owned(), "#d62728".to_owned()]),
                ),
        );
    }
    page.heading("Surface model and control-point path (Pudney Figs 45 and 47)");
    page.paragraph(
        "The completed model: each planar polygon segment in its own colour, perimeters in \
         dark grey, shared edges in thick red, corner vertices as black diamonds, point \
         segments as grey dots; the control point's path in blue. Drag to rotate, scroll to \
         zoom; the initial (a priori) segments and the ground truth start hidden: click their \
         legend entries. The axes frame the sensed model and the path.",
    );
    if !truth {
        page.paragraph(
            "no ground truth to show (no scenario.toml: a --scene run, or a point-cloud world)",
        );
    }
    let mut scene = bounds.map_or_else(
        || LayoutScene::new().aspect_mode(AspectMode::Data),
        |b| b.scene(),
    );
    scene = scene.drag_mode(plotly::layout::DragMode3D::Orbit);
    let layout = Layout::new()
        .height(760)
        .margin(Margin::new().left(0).right(0).top(30).bottom(0))
        .legend(Legend::new())
        .scene(scene);
    page.plot("view3d", &plot_of(traces, layout), 780, "view3d");

    evolution(&mut page, folder, bounds)?;
    step_plots(&mut page, &steps);
    Ok(page)
}

/// One small view per snapshot of `model_snapshots.json` (Figs 44 and 46),
/// all on the same axes, initial segments left out as in the thesis.
fn evolution(
    page: &mut Page,
    folder: &RunFolder,
    bounds: Option<Bounds>,
) -> Result<(), ReportError> {
    page.heading("Evolution of the model (Pudney Figs 44 and 46)");
    let path = folder.path(record::snapshots::MODEL_SNAPSHOTS_JSON);
    let snaps = folder.snapshots()?;
    page.paragraph(&format!(
        "The model after the number of sensor sets given above each view (every {} sets, and \
         at the end), on the same axes as the view above; initial segments are not shown, as \
         in the thesis.",
        snaps.stride_sets
    ));
    let mut last = None;
    for (i, s) in snaps.snapshots.iter().enumerate() {
        if last.is_some_and(|l| s.sets <= l) {
            return Err(ReportError::file(
                &path.display().to_string(),
                format!(
                    "`snapshots[{i}].sets`: {} does not follow {} (expected increasing set counts)",
                    s.sets,
                    last.unwrap_or_default()
                ),
            ));
        }
        last = Some(s.sets);
    }
    page.begin_grid();
    for s in &snaps.snapshots {
        let traces = model_traces(&s.model, Initial::Omit, false);
        let polygons = s
            .model
            .segments
            .iter()
            .filter(|g| matches!(g, SegmentJson::Polygon { initial: false, .. }))
            .count();
        let title = format!("after {} sets: {polygons} polygons", s.sets);
        let scene = bounds.map_or_else(
            || LayoutScene::new().aspect_mode(AspectMode::Data),
            |b| b.scene(),
        );
        let layout = Layout::new()
            .title(Title::with_text(&title))
            .height(380)
            .show_legend(false)
            .margin(Margin::new().left(0).right(0).top(40).bottom(0))
            .scene(scene);
        page.plot(
            &format!("evolution-{}", s.sets),
            &plot_of(traces, layout),
            390,
            "view3d small",
        );
    }
    page.end_grid();
    Ok(())
}

/// The categories of the mode axis: the thesis's five, then any other name
/// in the file in order of appearance.
fn mode_categories(modes: &[&str]) -> Vec<String> {
    let mut out: Vec<String> = MODES.iter().map(|m| (*m).to_owned()).collect();
    for m in modes {
        if !out.iter().any(|o| o == m) {
            out.push((*m).to_owned());
        }
    }
    out
}

fn step_plots(page: &mut Page, steps: &[StepRow]) {
    let step: Vec<usize> = steps.iter().map(|r| r.step as usize).collect();
    let modes: Vec<&str> = steps.iter().map(|r| r.mode.as_str()).collect();
    page.heading("Motion mode per step (P§3.4)");
    let categories = mode_categories(&modes);
    let mut traces: Vec<Box<dyn Trace>> = vec![
        Scatter::new(
            step.clone(),
            modes.iter().map(|m| (*m).to_owned()).collect(),
        )
        .mode(Mode::Lines)
        .name("mode")
        .show_legend(false)
        .line(Line::new().shape(LineShape::Hv).color("#c0c0c0").width(1.0)),
    ];
    for (c, name) in categories.iter().enumerate() {
        let x: Vec<usize> = (0..step.len())
            .filter(|&i| modes[i] == name)
            .map(|i| step[i])
            .collect();
        if x.is_empty() {
            continue;
        }
        let n = x.len();
        traces.push(
            Scatter::new(x, vec![name.clone(); n])
                .mode(Mode::Markers)
                .name(format!("{name} ({n} steps)"))
                .marker(
                    Marker::new()
                        .size(4)
                        .color(SEGMENT_COLOURS[c % SEGMENT_COLOURS.len()]),
                ),
        );
    }
    let layout = xy_layout("Motion mode per step", "step", "mode").y_axis(
        Axis::new()
            .title(Title::with_text("mode"))
            .type_(AxisType::Category)
            .category_order(CategoryOrder::Array)
            .category_array(categories),
    );
    page.plot("modes", &plot_of(traces, layout), 380, "xy");

    page.heading("Step times");
    let mut traces: Vec<Box<dyn Trace>> = Vec::new();
    let parts: [Part; 3] = [
        (|t| t.update_us, "surface model update"),
        (|t| t.direction_us, "direction (mode) choice"),
        (|t| t.kinematics_us, "actuator changes (kinematics)"),
    ];
    for (part, label) in parts {
        let v: Vec<Option<Real>> = steps.iter().map(|r| r.times.as_ref().map(part)).collect();
        let (x, y): (Vec<usize>, Vec<Real>) = step
            .iter()
            .zip(&v)
            .filter_map(|(k, v)| v.map(|v| (*k, v.max(0.01))))
            .unzip();
        if !x.is_empty() {
            traces.push(
                Scatter::new(x, y)
                    .mode(Mode::Lines)
                    .name(label)
                    .line(Line::new().width(1.0)),
            );
        }
    }
    let title = if traces.is_empty() {
        page.paragraph("The run was made with --no-timings: steps.csv has no step times.");
        "Time per step: not recorded (--no-timings)"
    } else {
        "Time per step, by part (log scale)"
    };
    let layout = xy_layout(title, "step", "µs").y_axis(
        Axis::new()
            .title(Title::with_text("µs"))
            .type_(AxisType::Log),
    );
    page.plot("times", &plot_of(traces, layout), 400, "xy");

    page.heading("Sensing and clearance per step");
    // As numbers, as the table holds them.
    let set_size: Vec<Real> = steps.iter().map(|r| r.set_size as Real).collect();
    let clearance: Vec<Option<Real>> = steps.iter().map(|r| r.link_clearance_m).collect();
    let (xc, yc): (Vec<usize>, Vec<Real>) = step
        .iter()
        .zip(&clearance)
        .filter_map(|(k, v)| v.map(|v| (*k, v)))
        .unzip();
    let traces: Vec<Box<dyn Trace>> = vec![
        Scatter::new(step.clone(), set_size)
            .mode(Mode::Lines)
            .name("sensor points in the set")
            .line(Line::new().width(1.0)),
        Scatter::new(xc, yc)
            .mode(Mode::Lines)
            .name("link clearance from the model (m)")
            .y_axis("y2")
            .line(Line::new().width(1.0)),
    ];
    let layout = xy_layout(
        "Sensor points per set and the links' clearance from the model",
        "step",
        "points",
    )
    .y_axis2(
        Axis::new()
            .title(Title::with_text("m"))
            .overlaying("y")
            .side(plotly::common::AxisSide::Right),
    );
    page.plot("sensing", &plot_of(traces, layout), 400, "xy");
}

/// A part of a step's time and its label.
type Part = (fn(&record::StepTimes) -> Real, &'static str);

#[cfg(test)]
mod tests {
    use super::*;
    use surface::EdgeJson;

    fn edge(shared_with: Option<u32>, corner_start: bool) -> EdgeJson {
        EdgeJson {
            shared_with,
            corresponding_edge: shared_with.map(|_| 0),
            corner_start,
        }
    }

    /// Two faces of a unit cube meeting along x = 1, z ∈ [0, 1] at y = 0:
    /// the top face has an L-shaped notch cut out, the side is a square.
    fn two_faces() -> ModelJson {
        ModelJson {
            segments: vec![
                SegmentJson::Polygon {
                    id: 3,
                    points: 40,
                    initial: false,
                    centroid: [0.5, 0.5, 1.0],
                    normal: [0.0, 0.0, 1.0],
                    // An L: the square [0,1]² without [0.5,1]×[0.5,1].
                    vertices: vec![
                        [0.0, 0.0, 1.0],
                        [1.0, 0.0, 1.0],
                        [1.0, 0.5, 1.0],
                        [0.5, 0.5, 1.0],
                        [0.5, 1.0, 1.0],
                        [0.0, 1.0, 1.0],
                    ],
                    edges: vec![
                        edge(Some(7), true),
                        edge(None, true),
                        edge(None, false),
                        edge(None, false),
                        edge(None, false),
                        edge(None, false),
                    ],
                },
                SegmentJson::Polygon {
                    id: 7,
                    points: 25,
                    initial: false,
                    centroid: [0.5, 0.0, 0.5],
                    normal: [0.0, -1.0, 0.0],
                    vertices: vec![
                        [0.0, 0.0, 0.0],
                        [1.0, 0.0, 0.0],
                        [1.0, 0.0, 1.0],
                        [0.0, 0.0, 1.0],
                    ],
                    edges: vec![
                        edge(None, false),
                        edge(None, false),
                        edge(Some(3), true),
                        edge(None, true),
                    ],
                },
                SegmentJson::Point {
                    id: 9,
                    points: 1,
                    centroid: [2.0, 2.0, 2.0],
                    sensing_axis: [0.0, 0.0, -1.0],
                },
            ],
            surfaces: vec![vec![3, 7], vec![9]],
        }
    }

    #[test]
    fn shared_edges_pair_up_and_corners_sit_on_them() {
        let m = two_faces();
        let (shared, corners) = shared_edges_and_corners(&m);
        assert_eq!(shared.len(), 2);
        assert_eq!(
            (shared[0].segment, shared[0].neighbour, shared[0].edge),
            (3, 7, 0)
        );
        assert_eq!(
            (shared[1].segment, shared[1].neighbour, shared[1].edge),
            (7, 3, 2)
        );
        // The two sides of a pair are the same segment, run in opposite senses.
        assert_eq!(shared[0].ends[0], shared[1].ends[1]);
        assert_eq!(shared[0].ends[1], shared[1].ends[0]);
        // Corners: the shared edge's ends, seen from both faces.
        let mut c: Vec<[Real; 3]> = corners.iter().map(|p| [p.x, p.y, p.z]).collect();
        c.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(
            c,
            vec![
                [0.0, 0.0, 1.0],
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 1.0],
                [1.0, 0.0, 1.0]
            ]
        );
    }

    #[test]
    fn polygons_are_triangulated_in_their_plane_with_their_area() {
        let m = two_faces();
        for (s, want) in m.segments.iter().zip([0.75, 1.0]) {
            let SegmentJson::Polygon {
                vertices, normal, ..
            } = s
            else {
                continue;
            };
            let tris = polygon_triangles(vertices, normal);
            let n = Vector3::new(normal[0], normal[1], normal[2]);
            let mut area = 0.0;
            for t in &tris {
                let [a, b, c] = t.map(|v| point(&vertices[v]));
                let cross = (b - a).cross(&(c - a));
                // Anticlockwise about the outward normal, like the perimeter.
                assert!(cross.dot(&n) > 0.0, "{t:?}");
                area += 0.5 * cross.norm();
            }
            assert!((area - want).abs() < 1e-12, "{area} vs {want}");
        }
    }

    #[test]
    fn unknown_modes_follow_the_thesis_modes() {
        assert_eq!(
            mode_categories(&["edge", "wander", "surface", "wander"]),
            ["surface", "segment", "edge", "point", "gap", "wander"]
        );
    }
}
