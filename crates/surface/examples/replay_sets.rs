//! Development aid: replays sensor sets from a JSON-lines file (the format of
//! [`surface::read_sets_jsonl`]) over the 4 m table as initial segment, and
//! prints update times and the polygons.
//! `cargo run --release -p surface --example replay_sets -- sets.jsonl [n] [dump]`
//! (`dump`: every vertex of every polygon after the last set; with `DIAG` set,
//! tries to merge every other segment into the polygon with the most points and
//! prints its distance and the merger's outcome).
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use geom::Point3;
use surface::{SurfaceConfig, SurfaceModel};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).expect("a sets.jsonl file");
    let n: usize = args.get(2).map_or(usize::MAX, |s| s.parse().unwrap());
    let dump = args.get(3).is_some_and(|s| s == "dump");
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let sets = surface::read_sets_jsonl(file, path).unwrap();
    let mut m = SurfaceModel::new(SurfaceConfig::default()).unwrap();
    m.add_initial_segment(&[
        Point3::new(-2.0, -2.0, 0.0),
        Point3::new(2.0, -2.0, 0.0),
        Point3::new(2.0, 2.0, 0.0),
        Point3::new(-2.0, 2.0, 0.0),
    ])
    .unwrap();
    let mut us = Vec::new();
    for s in sets.iter().take(n) {
        let t = std::time::Instant::now();
        m.update(s).unwrap();
        us.push(t.elapsed().as_secs_f64() * 1e6);
    }
    let mean = us.iter().sum::<f64>() / us.len().max(1) as f64;
    us.sort_by(f64::total_cmp);
    if !us.is_empty() {
        println!(
            "{} sets: update µs mean {mean:.1} median {:.1} p95 {:.1} max {:.1}",
            us.len(),
            us[us.len() / 2],
            us[us.len() * 95 / 100],
            us[us.len() - 1]
        );
    }
    let mut unshared = (0, 0.0);
    for seg in m.segments() {
        match (seg.as_polygon(), seg.as_point()) {
            (Some(p), _) => {
                let nrm = p.normal();
                for i in 0..p.len() {
                    if !p.is_initial() && p.edge(i).unwrap().share.is_none() {
                        let (a, b) = p.edge_points(i).unwrap();
                        unshared.0 += 1;
                        unshared.1 += (b - a).norm();
                    }
                }
                println!(
                    "  {:?}: {} vertices, {} points, area {:.3}, normal ({:.3}, {:.3}, {:.3})",
                    seg.id(),
                    p.len(),
                    seg.points(),
                    p.area(),
                    nrm.x,
                    nrm.y,
                    nrm.z
                );
                if dump {
                    for v in p.vertices() {
                        println!("    {:.4} {:.4} {:.4}", v.x, v.y, v.z);
                    }
                }
            }
            (_, Some(q)) => {
                let c = q.centroid();
                println!(
                    "  {:?}: point ({:.3}, {:.3}, {:.3})",
                    seg.id(),
                    c.x,
                    c.y,
                    c.z
                );
            }
            _ => {}
        }
    }
    if std::env::var("DIAG").is_ok() {
        use surface::testing::ModelInternals;
        let big = m
            .segments()
            .filter(|s| s.as_polygon().is_some_and(|p| !p.is_initial()))
            .max_by_key(|s| s.points())
            .map(surface::Segment::id)
            .unwrap();
        let others: Vec<_> = m
            .segments()
            .map(surface::Segment::id)
            .filter(|id| *id != big)
            .collect();
        for id in others {
            let seg = m.segment(id).unwrap();
            if seg.is_initial() {
                continue;
            }
            let d = match (seg.as_point(), seg.as_polygon()) {
                (Some(q), _) => m.polygon(big).unwrap().distance_to_point(&q.centroid()),
                (_, Some(p)) => p
                    .vertices()
                    .map(|v| m.polygon(big).unwrap().distance_to_point(&v))
                    .fold(f64::INFINITY, f64::min),
                _ => f64::NAN,
            };
            let mut c = m.clone();
            let r = c.try_merge(big, id);
            println!(
                "  {id:?} to {big:?}: distance {d:.4}, merge {:?} {:?}",
                r.map(|_| ()),
                seg.as_point().map(|q| (q.centroid(), q.axis_sum()))
            );
        }
    }
    let st = m.stats();
    println!(
        "model: {} segments, {} polygons, {} shared pairs, {} corners; unshared edges {} ({:.3} m)",
        st.segments, st.polygons, st.shared_edge_pairs, st.corner_vertices, unshared.0, unshared.1
    );
}
