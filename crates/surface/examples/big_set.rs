//! Time one update of a single large sensor set: `N` points on z = 1 with
//! ±1 mm noise, about 400 points per m² (`N`) or over a SIDE m square
//! (`N@SIDE`). Raise the model's `max_set_points` to go past the default.
//!
//! `cargo run --release -p surface --example big_set -- 10000 100000 4096@1`
#![allow(clippy::unwrap_used, missing_docs)]
use geom::{Point3, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::Instant;
use surface::{SensorSet, SurfaceConfig, SurfaceModel};

fn main() {
    for arg in std::env::args().skip(1) {
        // `N` (about 400 points per m²) or `N@SIDE` (a SIDE × SIDE m square).
        let (n, side) = if let Some((n, side)) = arg.split_once('@') {
            (n.parse::<usize>().unwrap(), side.parse::<f64>().unwrap())
        } else {
            let n = arg.parse::<usize>().unwrap();
            (n, (n as f64 / 400.0).sqrt().max(0.2))
        };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let points: Vec<Point3> = (0..n)
            .map(|_| {
                Point3::new(
                    rng.random_range(0.0..side),
                    rng.random_range(0.0..side),
                    1.0 + 0.002 * (rng.random::<f64>() - 0.5),
                )
            })
            .collect();
        let axes = vec![-Vector3::z(); n];
        let set = SensorSet::from_vectors(points, &axes).unwrap();
        let mut m = SurfaceModel::new(SurfaceConfig {
            max_set_points: usize::MAX,
            ..SurfaceConfig::default()
        })
        .unwrap();
        let t = Instant::now();
        m.update(&set).unwrap();
        println!(
            "{n} points over {side:.2} m square: {:.3} s, {:?}",
            t.elapsed().as_secs_f64(),
            m.stats()
        );
    }
}
