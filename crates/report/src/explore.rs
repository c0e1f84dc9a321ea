//! The report of a `surveyor explore` run (Paul ch. 6): the 3-D view of the
//! ground truth, cloud, mesh, discs by material with their segments, the
//! viewpoints and paths, the blast path; the plots of Figs 6.6, 6.12 and
//! 4.10, coverage and timings.

use crate::ReportError;
use crate::geometry::{Polylines, columns, plane_basis, simplify, stride_for};
use crate::page::{Page, plot_of, xy_layout};
use geom::{Isometry3, Point3, Real, Vector3};
use plotly::common::{Line, Marker, Mode, Title, Visible};
use plotly::layout::{AspectMode, Axis, BarMode, LayoutScene, Legend, Margin};
use plotly::{Bar, Layout, Mesh3D, Scatter, Scatter3D, Trace};
use record::blast::BlastPlan;
use record::{DiscTable, RunFolder, ViewpointRecord};
use std::path::Path;

/// At most this many cloud points are drawn.
pub const MAX_CLOUD_POINTS: usize = 60_000;
/// The TSDF mesh is simplified to at most this many triangles for display.
pub const MAX_MESH_TRIANGLES: usize = 80_000;
/// Length of the drawn scanner fans, metres.
const FAN_M: Real = 0.3;

/// A colour per material name (the five of SPEC §3.1; others cycle).
pub fn material_colour(name: &str, index: usize) -> &'static str {
    const OTHERS: [&str; 5] = ["#ff7f0e", "#2ca02c", "#9467bd", "#d62728", "#7f7f7f"];
    match name {
        "painted_metal" => "#1f77b4",
        "timber" => "#a0522d",
        "concrete" => "#bcbd22",
        "plastic" => "#e377c2",
        "stainless_steel" => "#17becf",
        _ => OTHERS[index % OTHERS.len()],
    }
}

/// Everything the 3-D view needs from the scenario.
struct Setup {
    robot: robot::Robot,
    world_from_base: Isometry3,
    half_fov_rad: Real,
    world: Option<scene::Scene>,
}

fn setup(folder: &RunFolder) -> Result<Setup, ReportError> {
    let loaded = crate::scenario_of(folder)?.ok_or_else(|| ReportError::File {
        file: folder
            .path(record::folder::SCENARIO_TOML)
            .display()
            .to_string(),
        message: "missing: an explore run folder holds the scenario it ran".into(),
    })?;
    let robot = loaded.build_robot()?;
    let half_fov_rad = loaded
        .scenario
        .scanner
        .clone()
        .unwrap_or_default()
        .config
        .half_fov_deg
        .to_radians();
    let world = match loaded.build_world()? {
        scene::World::Mesh(s) => Some(s),
        scene::World::Cloud(_) => None,
    };
    Ok(Setup {
        robot,
        world_from_base: loaded.scenario.world_from_base(),
        half_fov_rad,
        world,
    })
}

/// Build the page of the explore run in `folder`, naming it `shown`.
pub fn page(folder: &RunFolder, shown: &Path) -> Result<Page, ReportError> {
    let run = folder.summary_json();
    let viewpoints = folder.viewpoints()?;
    let scenario = folder.scenario().to_owned();
    let mut page = Page::new(&format!("surveyor explore: {scenario}"));
    page.intro(&format!(
        "AXBAM exploration (Paul 2010) of scenario {scenario}, run folder {}.",
        shown.display()
    ));

    let setup = setup(folder)?;
    let discs = folder.discs()?;
    view_3d(&mut page, folder, &viewpoints, &setup, &discs)?;
    information_plots(&mut page, &viewpoints);
    materials_section(&mut page, run, &viewpoints, &discs);
    Ok(page)
}

fn view_3d(
    page: &mut Page,
    folder: &RunFolder,
    viewpoints: &[ViewpointRecord],
    setup: &Setup,
    discs: &DiscTable,
) -> Result<(), ReportError> {
    let mut traces: Vec<Box<dyn Trace>> = Vec::new();
    let mut notes = Vec::new();
    if let Some(scene) = &setup.world {
        truth_meshes(scene, &mut traces);
    } else {
        notes.push("no ground truth to show (a point-cloud world)".to_owned());
    }
    let (count, shown) = folder.cloud_sample(|n| stride_for(n, MAX_CLOUD_POINTS))?;
    let stride = stride_for(count, MAX_CLOUD_POINTS);
    let [x, y, z] = columns(&shown);
    notes.push(format!(
        "cloud: 1 point in {stride} of {count} drawn ({})",
        shown.len()
    ));
    traces.push(
        Scatter3D::new(x, y, z.clone())
            .mode(Mode::Markers)
            .name(format!("cloud (1 in {stride})"))
            .visible(Visible::LegendOnly)
            .marker(Marker::new().size(1).color_array(z).color_scale(
                plotly::common::ColorScale::Palette(plotly::common::ColorScalePalette::Viridis),
            )),
    );
    let mesh = folder.mesh()?;
    let (shown, cell) = simplify(&mesh, MAX_MESH_TRIANGLES);
    if cell > 0.0 {
        notes.push(format!(
            "mesh: {} triangles simplified to {} by vertex clustering on {:.0} mm cells",
            mesh.triangles.len(),
            shown.triangles.len(),
            cell * 1000.0
        ));
    }
    traces.push(mesh_trace(&shown, "TSDF mesh", "#b0c4de", Visible::True));
    disc_traces(discs, &mut traces);
    viewpoint_traces(viewpoints, setup, &mut traces)?;
    if let Some(plan) = folder.blast_plan::<serde_json::Value>()? {
        blast_traces(&plan, &mut traces);
    }
    page.heading("3-D view");
    page.paragraph(
        "Drag to rotate, scroll to zoom; click a legend entry to show or hide it (the ground \
         truth and the cloud start hidden).",
    );
    for n in &notes {
        page.paragraph(n);
    }
    let layout = Layout::new()
        .height(800)
        .margin(Margin::new().left(0).right(0).top(30).bottom(0))
        .legend(Legend::new())
        .scene(
            LayoutScene::new()
                .aspect_mode(AspectMode::Data)
                .x_axis(Axis::new().title(Title::with_text("x (m)")))
                .y_axis(Axis::new().title(Title::with_text("y (m)")))
                .z_axis(Axis::new().title(Title::with_text("z (m)"))),
        );
    page.plot("view3d", &plot_of(traces, layout), 820, "view3d");
    Ok(())
}

fn mesh_trace(
    mesh: &geom::TriMesh,
    name: &str,
    colour: &'static str,
    visible: Visible,
) -> Box<Mesh3D<f32, f32, f32>> {
    let [x, y, z] = columns(&mesh.vertices);
    let idx = |c: usize| -> Vec<usize> { mesh.triangles.iter().map(|t| t[c] as usize).collect() };
    Mesh3D::new(x, y, z, Some(idx(0)), Some(idx(1)), Some(idx(2)))
        .name(name)
        .color(colour)
        .visible(visible)
        .show_legend(true)
        .flat_shading(true)
}

/// The ground truth, one mesh per material, hidden until clicked in the
/// legend (both kinds of report draw it).
pub(crate) fn truth_meshes(scene: &scene::Scene, traces: &mut Vec<Box<dyn Trace>>) {
    for (m, material) in scene.materials().iter().enumerate() {
        let mut mesh = geom::TriMesh {
            vertices: Vec::new(),
            triangles: Vec::new(),
        };
        for o in scene
            .objects()
            .iter()
            .filter(|o| usize::from(o.material.0) == m)
        {
            for t in &scene.mesh().triangles[o.triangles.clone()] {
                let base = u32::try_from(mesh.vertices.len()).unwrap_or(u32::MAX);
                mesh.vertices
                    .extend(t.iter().map(|&v| scene.mesh().vertices[v as usize]));
                mesh.triangles.push([base, base + 1, base + 2]);
            }
        }
        if mesh.triangles.is_empty() {
            continue;
        }
        traces.push(
            Mesh3D::new(
                columns(&mesh.vertices)[0].clone(),
                columns(&mesh.vertices)[1].clone(),
                columns(&mesh.vertices)[2].clone(),
                Some(mesh.triangles.iter().map(|t| t[0] as usize).collect()),
                Some(mesh.triangles.iter().map(|t| t[1] as usize).collect()),
                Some(mesh.triangles.iter().map(|t| t[2] as usize).collect()),
            )
            .name(format!("truth: {}", material.name))
            .legend_group("truth")
            .color(material_colour(&material.name, m))
            .opacity(0.35)
            .show_legend(true)
            .visible(Visible::LegendOnly),
        );
    }
}

/// Discs coloured by their most probable material, solid where it is
/// identified (`p ≥ 0.8`) and faded where it is not yet, apart in grey
/// while every material is equally likely; drawn as 8-sided fans 3 mm
/// above their plane, and each segment's outline (the convex hull of its
/// discs' rims in the segment's mean plane).
fn disc_traces(table: &DiscTable, traces: &mut Vec<Box<dyn Trace>>) {
    let discs = &table.discs;
    let segment = &table.segment;
    let names = &table.material_names;
    // The MAP material and whether it is identified, or None while the
    // belief is still flat.
    let map: Vec<Option<(usize, bool)>> =
        (0..discs.len()).map(|i| most_probable(table, i)).collect();
    let centre = |i: usize| discs[i].centre;
    let normal = |i: usize| discs[i].normal.into_inner();
    let rim = |i: usize| -> Vec<Point3> {
        let (u, v) = plane_basis(&normal(i));
        (0..8)
            .map(|k| {
                let a = f64::from(k) * std::f64::consts::TAU / 8.0;
                centre(i) + normal(i) * 0.003 + discs[i].radius_m * (a.cos() * u + a.sin() * v)
            })
            .collect()
    };
    let groups: Vec<Option<(usize, bool)>> = std::iter::once(None)
        .chain((0..names.len()).flat_map(|m| [Some((m, true)), Some((m, false))]))
        .collect();
    for g in groups {
        let members: Vec<usize> = (0..discs.len()).filter(|&i| map[i] == g).collect();
        if members.is_empty() {
            continue;
        }
        let mut mesh = geom::TriMesh {
            vertices: Vec::new(),
            triangles: Vec::new(),
        };
        for &i in &members {
            let base = u32::try_from(mesh.vertices.len()).unwrap_or(u32::MAX);
            mesh.vertices.push(centre(i) + normal(i) * 0.003);
            mesh.vertices.extend(rim(i));
            for k in 0..8u32 {
                mesh.triangles
                    .push([base, base + 1 + k, base + 1 + (k + 1) % 8]);
            }
        }
        let n = members.len();
        let trace = match g {
            Some((m, true)) => mesh_trace(
                &mesh,
                &format!("discs: {}, p ≥ 0.8 ({n})", names[m]),
                material_colour(&names[m], m),
                Visible::True,
            ),
            Some((m, false)) => mesh_trace(
                &mesh,
                &format!("discs: {}, p < 0.8 ({n})", names[m]),
                material_colour(&names[m], m),
                Visible::True,
            )
            .opacity(0.35),
            // Discs with no material information start hidden: the mesh
            // shows there.
            None => mesh_trace(
                &mesh,
                &format!("discs: no material information ({n})"),
                "#c8c8c8",
                Visible::LegendOnly,
            ),
        };
        traces.push(trace);
    }
    let mut by_segment: std::collections::BTreeMap<usize, Vec<usize>> =
        std::collections::BTreeMap::new();
    for (i, &s) in segment.iter().enumerate() {
        by_segment.entry(s).or_default().push(i);
    }
    let segments = by_segment.len();
    let mut outlines = Polylines::default();
    for members in by_segment.values() {
        let mean_n = members.iter().map(|&i| normal(i)).sum::<Vector3>();
        let Some(mean_n) = mean_n.try_normalize(1e-9) else {
            continue;
        };
        let origin = centre(members[0]);
        let (u, v) = plane_basis(&mean_n);
        let flat: Vec<geom::Point2> = members
            .iter()
            .flat_map(|&i| rim(i))
            .map(|p| geom::Point2::new((p - origin).dot(&u), (p - origin).dot(&v)))
            .collect();
        let offset = members
            .iter()
            .map(|&i| (centre(i) - origin).dot(&mean_n))
            .sum::<Real>()
            / members.len() as Real
            + 0.004;
        let mut ring: Vec<Point3> = geom::polygon2::convex_hull(flat)
            .iter()
            .map(|q| origin + q.x * u + q.y * v + offset * mean_n)
            .collect();
        if let Some(first) = ring.first().copied() {
            ring.push(first);
        }
        outlines.push(&ring);
    }
    if !outlines.is_empty() {
        let [x, y, z] = outlines.xyz;
        traces.push(
            Scatter3D::new(x, y, z)
                .mode(Mode::Lines)
                .name(format!("segment outlines ({segments})"))
                .connect_gaps(false)
                .line(Line::new().color("#202020").width(2.0)),
        );
    }
}

/// Scanner fans at the viewpoints (the scan plane's field, `FAN_M` long) and
/// the scanner's path along the executed motions, per stage.
fn viewpoint_traces(
    viewpoints: &[ViewpointRecord],
    s: &Setup,
    traces: &mut Vec<Box<dyn Trace>>,
) -> Result<(), ReportError> {
    let scanner = |q: &[Real]| -> Result<Option<Isometry3>, ReportError> {
        Ok(s.robot.scanner_pose(q)?.map(|p| s.world_from_base * p))
    };
    let colours = ["#ff7f0e", "#9467bd"];
    for st in [1, 2] {
        let mut fans = Polylines::default();
        let mut apex = Vec::new();
        let mut labels = Vec::new();
        for (i, q) in viewpoints
            .iter()
            .map(|r| &r.joints)
            .enumerate()
            .filter(|(i, _)| viewpoints[*i].stage == st)
        {
            let Some(pose) = scanner(q)? else {
                continue;
            };
            let o = pose.translation.vector.into();
            let ray = |b: Real| pose * (Point3::from(sensor::sweep::beam_direction(b) * FAN_M));
            let n = 8;
            let arc: Vec<Point3> = (0..=n)
                .map(|k| ray(-s.half_fov_rad + 2.0 * s.half_fov_rad * f64::from(k) / f64::from(n)))
                .collect();
            let mut fan = vec![o];
            fan.extend(arc.iter().copied());
            fan.push(o);
            fans.push(&fan);
            fans.push(&[o, ray(0.0)]);
            apex.push(o);
            labels.push(format!("viewpoint {i}"));
        }
        if apex.is_empty() {
            continue;
        }
        let [x, y, z] = fans.xyz;
        let colour = colours[usize::from(st == 2)];
        traces.push(
            Scatter3D::new(x, y, z)
                .mode(Mode::Lines)
                .name(format!("stage {st} viewpoints: scanner fans"))
                .legend_group(format!("stage{st}"))
                .line(Line::new().color(colour).width(3.0)),
        );
        let [x, y, z] = columns(&apex);
        traces.push(
            Scatter3D::new(x, y, z)
                .mode(Mode::Markers)
                .name(format!("stage {st} viewpoints"))
                .legend_group(format!("stage{st}"))
                .show_legend(false)
                .hover_text_array(labels)
                .marker(Marker::new().size(4).color(colour)),
        );
    }
    for st in [1, 2] {
        let mut lines = Polylines::default();
        for r in viewpoints
            .iter()
            .filter(|r| r.stage == st && r.path.len() >= 2)
        {
            let mut pts = Vec::new();
            for w in r.path.windows(2) {
                for step in 0..=8 {
                    let t = f64::from(step) / 8.0;
                    let qi: Vec<Real> = w[0]
                        .iter()
                        .zip(&w[1])
                        .map(|(a, b)| a + t * (b - a))
                        .collect();
                    if let Some(p) = scanner(&qi)? {
                        pts.push(Point3::from(p.translation.vector));
                    }
                }
            }
            lines.push(&pts);
        }
        if lines.is_empty() {
            continue;
        }
        let [x, y, z] = lines.xyz;
        traces.push(
            Scatter3D::new(x, y, z)
                .mode(Mode::Lines)
                .name(format!("stage {st} motions (scanner path)"))
                .connect_gaps(false)
                .line(
                    Line::new()
                        .color(colours[usize::from(st == 2)])
                        .width(2.0)
                        .dash(plotly::common::DashType::Dot),
                ),
        );
    }
    Ok(())
}

/// The blast path: the nozzle tips in the plan's order, segment by segment.
fn blast_traces(plan: &BlastPlan<serde_json::Value>, traces: &mut Vec<Box<dyn Trace>>) {
    let mut lines = Polylines::default();
    let mut count = 0;
    for s in &plan.segments {
        let mut pts: Vec<Point3> = s.targets.iter().map(|t| Point3::from(t.nozzle)).collect();
        count += pts.len();
        if pts.len() == 1 {
            pts.push(pts[0]);
        }
        lines.push(&pts);
    }
    if lines.is_empty() {
        return;
    }
    let [x, y, z] = lines.xyz;
    traces.push(
        Scatter3D::new(x, y, z)
            .mode(Mode::LinesMarkers)
            .name(format!("blast path: nozzle tips ({count})"))
            .connect_gaps(false)
            .visible(Visible::LegendOnly)
            .marker(Marker::new().size(2).color("#d62728"))
            .line(Line::new().color("#d62728").width(1.5)),
    );
}

/// The plots of the run's series: Figs 6.6, 6.12 and 4.10, coverage and
/// effort, times.
fn information_plots(page: &mut Page, vp: &[ViewpointRecord]) {
    candidate_plots(page, vp);
    information_plot(page, vp);
    prediction_plot(page, vp);
    effort_plots(page, vp);
}

/// Fig. 6.6: the objectives of every candidate per Stage One decision.
fn candidate_plots(page: &mut Page, vp: &[ViewpointRecord]) {
    page.heading("Objectives of the candidates, per Stage One decision (Paul Fig. 6.6)");
    {
        let mut ck = Vec::new();
        let mut cf: Vec<[Real; 4]> = Vec::new();
        let mut front = Vec::new();
        let mut chosen = Vec::new();
        for r in vp {
            for c in &r.scored {
                ck.push(r.k);
                cf.push(c.f);
                front.push(usize::from(c.front));
                chosen.push(usize::from(r.f == Some(c.f)));
            }
        }
        let titles = [
            ("f1", "f1: weighted geometric information left"),
            ("f2", "f2: C-space information left"),
            ("f3", "f3: joint travel (rad)"),
            ("f4", "f4: dist(Q), smallest over the sweep"),
        ];
        for (j, (name, title)) in titles.into_iter().enumerate() {
            let f: Vec<Real> = cf.iter().map(|f| f[j]).collect();
            let pick = |keep: &dyn Fn(usize) -> bool| -> (Vec<usize>, Vec<Real>) {
                (0..f.len())
                    .filter(|&i| keep(i))
                    .map(|i| (ck[i], f[i]))
                    .unzip()
            };
            let (x0, y0) = pick(&|i| front[i] == 0);
            let (x1, y1) = pick(&|i| front[i] == 1 && chosen[i] == 0);
            let (x2, y2) = pick(&|i| chosen[i] == 1);
            let traces: Vec<Box<dyn Trace>> = vec![
                Scatter::new(x0, y0)
                    .mode(Mode::Markers)
                    .name("candidate")
                    .marker(Marker::new().size(4).color("#bbbbbb")),
                Scatter::new(x1, y1)
                    .mode(Mode::Markers)
                    .name("on the Pareto front")
                    .marker(Marker::new().size(5).color("#1f77b4")),
                Scatter::new(x2, y2)
                    .mode(Mode::Markers)
                    .name("chosen")
                    .marker(Marker::new().size(9).color("#d62728")),
            ];
            page.plot(
                name,
                &plot_of(traces, xy_layout(title, "viewpoint k", name)),
                380,
                "xy",
            );
        }
    }
}

/// Fig. 6.12: information remaining over viewpoints, each relative to its first value.
fn information_plot(page: &mut Page, vp: &[ViewpointRecord]) {
    let k: Vec<usize> = vp.iter().map(|r| r.k).collect();
    page.heading("Information remaining over viewpoints (Paul Fig. 6.12)");
    let mut traces: Vec<Box<dyn Trace>> = Vec::new();
    let series: [(&[Option<Real>], &str); 3] = [
        (
            &vp.iter().map(|r| Some(r.h1_weighted)).collect::<Vec<_>>(),
            "H1 (weighted, eq. 4.11)",
        ),
        (
            &vp.iter().map(|r| Some(r.h2)).collect::<Vec<_>>(),
            "H2 (C-space, eq. 4.14)",
        ),
        (
            &vp.iter().map(|r| r.h3).collect::<Vec<_>>(),
            "H3 (materials, eq. 4.17)",
        ),
    ];
    for (v, label) in series {
        let Some(first) = v.iter().flatten().copied().find(|x| *x != 0.0) else {
            continue;
        };
        let (x, y): (Vec<usize>, Vec<Real>) = k
            .iter()
            .zip(v)
            .filter_map(|(k, v)| v.map(|v| (*k, v / first)))
            .unzip();
        traces.push(
            Scatter::new(x, y)
                .mode(Mode::LinesMarkers)
                .name(format!("{label}, first value {first:.4e}")),
        );
    }
    page.plot(
        "information",
        &plot_of(
            traces,
            xy_layout(
                "Information remaining (relative to its first value)",
                "viewpoint k",
                "fraction",
            ),
        ),
        400,
        "xy",
    );
}

/// Fig. 4.10: the information predicted to remain against what remained.
fn prediction_plot(page: &mut Page, vp: &[ViewpointRecord]) {
    let k: Vec<usize> = vp.iter().map(|r| r.k).collect();
    page.heading("Predicted and obtained information (Paul Fig. 4.10)");
    let predicted: Vec<Option<Real>> = vp.iter().map(|r| r.predicted_h1_weighted).collect();
    let actual: Vec<Real> = vp.iter().map(|r| r.h1_weighted).collect();
    let (xp, yp): (Vec<usize>, Vec<Real>) = k
        .iter()
        .zip(&predicted)
        .filter_map(|(k, v)| v.map(|v| (*k, v)))
        .unzip();
    let traces: Vec<Box<dyn Trace>> = vec![
        Scatter::new(xp, yp)
            .mode(Mode::LinesMarkers)
            .name("predicted to remain after the chosen view (f1)"),
        Scatter::new(k.clone(), actual)
            .mode(Mode::LinesMarkers)
            .name("remaining after its sweep"),
    ];
    page.plot(
        "prediction",
        &plot_of(
            traces,
            xy_layout(
                "Weighted H1: predicted and obtained",
                "viewpoint k",
                "H1 (weighted)",
            ),
        ),
        400,
        "xy",
    );
}

/// Coverage of A1, joint travel and the times per viewpoint.
fn effort_plots(page: &mut Page, vp: &[ViewpointRecord]) {
    let k: Vec<usize> = vp.iter().map(|r| r.k).collect();
    page.heading("Coverage and effort");
    let cov: Vec<Option<Real>> = vp.iter().map(|r| r.coverage_a1).collect();
    let (xc, yc): (Vec<usize>, Vec<Real>) = k
        .iter()
        .zip(&cov)
        .filter_map(|(k, v)| v.map(|v| (*k, 100.0 * v)))
        .unzip();
    let travel: Vec<Real> = vp.iter().map(|r| r.joint_travel).collect();
    let traces: Vec<Box<dyn Trace>> = vec![
        Scatter::new(xc, yc)
            .mode(Mode::LinesMarkers)
            .name("A1 surfaces covered (%)"),
        Scatter::new(k.clone(), travel)
            .mode(Mode::LinesMarkers)
            .name("joint travel to the viewpoint (rad)")
            .y_axis("y2"),
    ];
    let layout = xy_layout(
        "Coverage of the A1 surfaces and joint travel",
        "viewpoint k",
        "covered (%)",
    )
    .y_axis2(
        Axis::new()
            .title(Title::with_text("rad"))
            .overlaying("y")
            .side(plotly::common::AxisSide::Right),
    );
    page.plot("coverage", &plot_of(traces, layout), 400, "xy");

    let mut traces: Vec<Box<dyn Trace>> = Vec::new();
    let times: [Series; 4] = [
        (|r| r.decision_ms, "decision"),
        (|r| r.plan_ms, "of it, choice and path planning"),
        (|r| r.sweep_ms, "sweep"),
        (|r| r.integrate_ms, "integration"),
    ];
    for (time, label) in times {
        traces.push(Bar::new(k.clone(), vp.iter().map(time).collect::<Vec<Real>>()).name(label));
    }
    let layout = xy_layout("Time per viewpoint", "viewpoint k", "ms").bar_mode(BarMode::Group);
    page.plot("timings", &plot_of(traces, layout), 400, "xy");
}

/// A per-viewpoint series of the time plots and its label.
type Series = (fn(&ViewpointRecord) -> Real, &'static str);

/// Disc `i`'s most probable material and whether it is identified (`p ≥
/// 0.8`), `None` while its belief is flat (or there is none).
fn most_probable(table: &DiscTable, i: usize) -> Option<(usize, bool)> {
    let p: &[Real] = table
        .posterior
        .as_ref()
        .and_then(|p| p.get(i))
        .map_or(&[], Vec::as_slice);
    let (best, &top) = p
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))?;
    let min = p.iter().copied().fold(Real::INFINITY, Real::min);
    (top - min > 1e-6).then_some((best, top >= IDENTIFIED_P))
}

/// A disc's material counts as identified at this probability of its most
/// probable material (`explore::lrc::IDENTIFIED_P`).
const IDENTIFIED_P: Real = 0.8;

/// Materials (A§3.3, §4.4): the identified share viewpoint by viewpoint
/// against the material oracle's, beside H3 (Fig. 6.12), and the true ×
/// most probable material of the discs.
fn materials_section(
    page: &mut Page,
    run: &serde_json::Value,
    vp: &[ViewpointRecord],
    discs: &DiscTable,
) {
    let rows: Vec<&ViewpointRecord> = vp.iter().filter(|r| r.discs_identified.is_some()).collect();
    if rows.is_empty() || discs.posterior.is_none() {
        return;
    }
    page.heading("Materials identified, viewpoint by viewpoint");
    let mi = &run["material_identification"];
    let share = |key: &str| -> Vec<Real> {
        mi[key]
            .as_array()
            .map(|a| a.iter().filter_map(serde_json::Value::as_f64).collect())
            .unwrap_or_default()
    };
    let run_curve = share("identified_after_viewpoints");
    let oracle_curve: Vec<Real> = mi["oracle"]["identified_after_viewpoints"]
        .as_array()
        .map(|a| a.iter().filter_map(serde_json::Value::as_f64).collect())
        .unwrap_or_default();
    let n: Vec<usize> = (0..rows.len()).collect();
    let mut traces: Vec<Box<dyn Trace>> = Vec::new();
    let y_title = if run_curve.len() == rows.len() {
        page.paragraph(
            "The share of A2's true surface whose disc's most probable material has p ≥ 0.8, \
             when Stage Two starts (Stage One's sweeps classified) and after each of its \
             viewpoints, beside what viewpoints chosen knowing the scene (the material oracle, \
             greedy) identify after as many; and the material information left, H3 (eq. 4.17, \
             Fig. 6.12), relative to Stage Two's start.",
        );
        traces.push(
            Scatter::new(n.clone(), run_curve.iter().map(|x| 100.0 * x).collect())
                .mode(Mode::LinesMarkers)
                .name("the run"),
        );
        let k = rows.len().min(oracle_curve.len() + 1);
        let oracle: Vec<Real> = std::iter::once(0.0)
            .chain(oracle_curve.iter().map(|x| 100.0 * x))
            .take(k)
            .collect();
        traces.push(
            Scatter::new((0..k).collect(), oracle)
                .mode(Mode::LinesMarkers)
                .name("material oracle (greedy, knowing the scene)")
                .line(Line::new().dash(plotly::common::DashType::Dash)),
        );
        if let Some(all) = mi["oracle"]["identifiable"].as_f64() {
            traces.push(
                Scatter::new(vec![0, rows.len() - 1], vec![100.0 * all; 2])
                    .mode(Mode::Lines)
                    .name("identifiable from some safe pose (oracle)")
                    .line(
                        Line::new()
                            .color("#888888")
                            .dash(plotly::common::DashType::Dot),
                    ),
            );
        }
        "A2 identified (%)"
    } else {
        page.paragraph(
            "The discs whose most probable material has p ≥ 0.8, when Stage Two starts (Stage \
             One's sweeps classified) and after each of its viewpoints (no material oracle in \
             this run), and the material information left, H3 (eq. 4.17, Fig. 6.12), relative \
             to Stage Two's start.",
        );
        traces.push(
            Scatter::new(
                n.clone(),
                rows.iter()
                    .map(|r| r.discs_identified.unwrap_or(0) as Real)
                    .collect(),
            )
            .mode(Mode::LinesMarkers)
            .name("discs identified"),
        );
        "discs identified"
    };
    if let Some(first) = rows[0].h3.filter(|h| *h > 0.0) {
        traces.push(
            Scatter::new(
                n,
                rows.iter()
                    .map(|r| r.h3.map_or(Real::NAN, |h| h / first))
                    .collect(),
            )
            .mode(Mode::LinesMarkers)
            .name("H3 left (right axis)")
            .y_axis("y2"),
        );
    }
    let layout = xy_layout(
        "Identified materials against the material oracle",
        "Stage Two viewpoints",
        y_title,
    )
    .y_axis2(
        Axis::new()
            .title(Title::with_text("H3 left"))
            .tick_format(".3f")
            .overlaying("y")
            .side(plotly::common::AxisSide::Right),
    )
    .legend(Legend::new().x(1.08));
    page.plot("materials", &plot_of(traces, layout), 400, "xy");
    confusion_table(page, discs);
}

/// The true × most probable material of the discs with a known true
/// material.
fn confusion_table(page: &mut Page, discs: &DiscTable) {
    let names = &discs.material_names;
    let Some(posterior) = &discs.posterior else {
        return;
    };
    let m = names.len();
    // Per true material: identified as each material, not identified
    // (p < 0.8), no information.
    let mut counts = vec![vec![0usize; m + 2]; m];
    for (i, t) in discs.true_material.iter().enumerate() {
        let Some(t) = t.filter(|t| *t < m) else {
            continue;
        };
        if posterior.get(i).is_none() {
            continue;
        }
        match most_probable(discs, i) {
            Some((best, true)) => counts[t][best] += 1,
            Some((_, false)) => counts[t][m] += 1,
            None => counts[t][m + 1] += 1,
        }
    }
    page.heading("True and most probable materials of the discs");
    page.paragraph(
        "Per true material (the nearest true surface's), the discs identified (p ≥ 0.8) as each \
         material, those with some information but below 0.8, and those without any; the last \
         column is the share of the identified that is right.",
    );
    let mut header = vec!["true \\ most probable".to_owned()];
    header.extend(names.iter().cloned());
    header.extend([
        "p < 0.8".to_owned(),
        "no information".to_owned(),
        "right".to_owned(),
    ]);
    let table: Vec<Vec<String>> = counts
        .iter()
        .enumerate()
        .map(|(t, row)| {
            let identified: usize = row[..m].iter().sum();
            let mut cells = vec![names[t].clone()];
            cells.extend(row.iter().map(usize::to_string));
            cells.push(if identified > 0 {
                format!("{:.1} %", 100.0 * row[t] as Real / identified as Real)
            } else {
                "–".to_owned()
            });
            cells
        })
        .collect();
    page.grid_table("materials-confusion", &header, &table);
}
