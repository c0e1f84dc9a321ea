//! Material belief (Paul §4.4): Bayes updates, H3 per disc and in total.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use geom::{Point3, UnitVector3, Vector3};
use map::key::VoxelKey;
use map::material::{MaterialBelief, MaterialConfig};
use map::sld::Disc;
use std::hint::black_box;

fn material(c: &mut Criterion) {
    // 40 000 surface voxels (Paul Table 6.1: n_v = 41 070 voxels).
    let mut belief = MaterialBelief::new(MaterialConfig::default()).unwrap();
    let keys: Vec<VoxelKey> = (0..200)
        .flat_map(|x| (0..200).map(move |y| VoxelKey::new(x, y, 152)))
        .collect();
    for &k in &keys {
        belief.insert_surface(k);
    }
    let z = [0.1, 0.6, 0.1, 0.1, 0.1];
    let disc = Disc {
        centre: Point3::new(1.0, 1.0, 1.525),
        normal: UnitVector3::new_unchecked(-Vector3::z()),
        radius_m: 0.04,
        points: 50,
    };
    let mut group = c.benchmark_group("material");
    group.bench_function("update 1 000 voxels", |b| {
        b.iter(|| {
            for k in &keys[..1000] {
                belief.update(black_box(*k), &z).unwrap();
            }
        });
    });
    group.bench_function("h3_disc (μ = 40 mm over 1 cm voxels)", |b| {
        b.iter(|| belief.h3_disc(black_box(&disc)));
    });
    group.bench_function("h3_total (40 000 voxels)", |b| {
        b.iter(|| black_box(&belief).h3_total());
    });
    group.finish();
}

criterion_group!(benches, material);
criterion_main!(benches);
