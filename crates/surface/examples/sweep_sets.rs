//! Writes a scripted raster sweep of a built-in scene (cube, block1, block2,
//! cylinder) by point3's 26 sensors at standoff 0.1 m as `surveyor model` input:
//! one JSON line per sensor set, `{"points": [...], "axes": [...]}`.
//!
//! `cargo run --release -p surface --example sweep_sets -- block1 [NOISE_SIGMA] > block1.jsonl`
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

#[path = "../tests/support/mod.rs"]
mod support;

use std::io::Write;

fn main() {
    let mut args = std::env::args().skip(1);
    let scene = args.next().unwrap_or_else(|| "cube".into());
    let noise_sigma = args
        .next()
        .map_or(0.0, |s| s.parse().expect("NOISE_SIGMA in metres"));
    let sweep = support::Sweep {
        noise_sigma,
        ..support::Sweep::default()
    };
    let out = std::io::stdout();
    let mut out = std::io::BufWriter::new(out.lock());
    for set in support::sweep_sets(&scene, &sweep) {
        let points: Vec<[f64; 3]> = set.points.iter().map(|p| [p.x, p.y, p.z]).collect();
        let axes: Vec<[f64; 3]> = set.axes.iter().map(|a| [a.x, a.y, a.z]).collect();
        let line = serde_json::json!({ "points": points, "axes": axes });
        writeln!(out, "{line}").unwrap();
    }
}
