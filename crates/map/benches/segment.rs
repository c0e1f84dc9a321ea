//! Map segmentation (Paul §5.3): the ~4 000 discs of the fused bridge1
//! section (Paul: "several thousand SLDs … in less than a second").
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

#[path = "../tests/sld_support/mod.rs"]
mod support;

use criterion::{Criterion, criterion_group, criterion_main};
use map::segment::{SegmentConfig, segment_discs};
use map::sld::{Orientation, SldConfig, generate_discs};
use std::hint::black_box;

fn segment(c: &mut Criterion) {
    let mut f = support::fused_bridge1(5, 0.4, 11);
    support::crop_x(&mut f, 1.0);
    let discs = generate_discs(
        &f.points,
        Orientation::SensorOrigins(&f.origins),
        &SldConfig::default(),
        1,
    )
    .unwrap()
    .discs;
    let poses: Vec<[f64; 6]> = discs
        .iter()
        .map(|d| {
            [
                d.centre.y.atan2(d.centre.x),
                0.3 * d.centre.z,
                0.5 * d.centre.coords.norm(),
                0.0,
                d.centre.y.signum(),
                0.0,
            ]
        })
        .collect();
    let cfg = SegmentConfig::default();
    let mut group = c.benchmark_group("segment");
    group.bench_function(format!("{} discs", discs.len()), |b| {
        b.iter(|| segment_discs(black_box(&discs), None, &cfg).unwrap());
    });
    group.bench_function(format!("{} discs with poses", discs.len()), |b| {
        b.iter(|| segment_discs(black_box(&discs), Some(&poses), &cfg).unwrap());
    });
    group.finish();
}

criterion_group!(benches, segment);
criterion_main!(benches);
