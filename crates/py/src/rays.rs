//! Rays from NumPy rows, cast as `surveyor raycast` casts them.
//!
//! [`ray_records`] checks each ray and packs it as a record of the rays file
//! `surveyor raycast` reads (`scene::io::rays`): six `f32`, the origin then a
//! unit direction, under the same rules (finite values; `|‖d‖² − 1|` at most
//! [`DIRECTION_TOLERANCE`] in `f32`). [`cast`] then makes the CLI's call,
//! [`scene::Scene::cast_rays_f32`] on the rayon pool, so the distances are the
//! CLI's bit for bit; the face of each hit comes from
//! [`scene::Scene::first_hit_f32`], the single-ray walk of the same tree, which
//! the scene crate documents as giving the same hits as the batch.

use rayon::prelude::*;
use scene::Scene;
use scene::io::rays::{DIRECTION_TOLERANCE, RayRecord};

/// Face id of a ray that hits nothing.
pub const MISS_FACE: i64 = -1;

/// The rays of `origins` and `directions` (each `3 n` values, row after
/// row) as rays-file records; the first bad ray is an error naming it.
pub fn ray_records(origins: &[f64], directions: &[f64]) -> Result<Vec<RayRecord>, String> {
    if origins.len() != directions.len() {
        return Err(format!(
            "origins has {} rows and directions {}: give one direction per origin",
            origins.len() / 3,
            directions.len() / 3
        ));
    }
    origins
        .chunks_exact(3)
        .zip(directions.chunks_exact(3))
        .enumerate()
        .map(|(i, (o, d))| ray_record(i, [o[0], o[1], o[2]], [d[0], d[1], d[2]]))
        .collect()
}

/// One ray, checked (module docs).
fn ray_record(i: usize, o: [f64; 3], d: [f64; 3]) -> Result<RayRecord, String> {
    let show = |v: [f64; 3]| format!("({}, {}, {})", v[0], v[1], v[2]);
    if o.iter().any(|v| !v.is_finite()) {
        return Err(format!(
            "origins[{i}] is {}: every coordinate must be a finite number (NaN or infinity found)",
            show(o)
        ));
    }
    if d.iter().any(|v| !v.is_finite()) {
        return Err(format!(
            "directions[{i}] is {}: every component must be a finite number (NaN or infinity found)",
            show(d)
        ));
    }
    if d.iter().all(|v| *v == 0.0) {
        return Err(format!(
            "directions[{i}] is {}: a zero-length direction; each ray needs a unit direction",
            show(d)
        ));
    }
    let o32 = o.map(|v| v as f32);
    if o32.iter().any(|v| !v.is_finite()) {
        return Err(format!(
            "origins[{i}] is {}: beyond the single-precision range (±3.4e38) rays are cast in",
            show(o)
        ));
    }
    let d32 = d.map(|v| v as f32);
    let n2 = d32[0] * d32[0] + d32[1] * d32[1] + d32[2] * d32[2];
    // Finite components: n2 is finite or +inf, never NaN.
    if (n2 - 1.0).abs() > DIRECTION_TOLERANCE {
        return Err(format!(
            "directions[{i}] is {}, of length {}: expected a unit vector (|‖d‖² − 1| ≤ \
             {DIRECTION_TOLERANCE}; normalise with d / numpy.linalg.norm(d, axis=1, keepdims=True))",
            show(d),
            Into::<f64>::into(n2).sqrt()
        ));
    }
    Ok([o32[0], o32[1], o32[2], d32[0], d32[1], d32[2]])
}

/// `max_range` as the `f32` bound of the cast: a number ≥ 0 (`inf` for no
/// bound).
pub fn range_bound(max_range: f64) -> Result<f32, String> {
    if max_range.is_nan() || max_range < 0.0 {
        return Err(format!(
            "max_range is {max_range}: expected a distance ≥ 0 in metres (inf for no bound)"
        ));
    }
    Ok(max_range as f32)
}

/// Fewest hits one rayon task looks up the faces of.
const FACE_PIECE: usize = 256;

/// The first hit of every ray within `t_max`: its distance (`+inf` on a
/// miss), from [`Scene::cast_rays_f32`] as `surveyor raycast` computes it,
/// and its face ([`MISS_FACE`] on a miss). Runs on the calling rayon pool.
pub fn cast(scene: &Scene, rays: &[RayRecord], t_max: f32) -> (Vec<f32>, Vec<i64>) {
    let mut distances = vec![0f32; rays.len()];
    scene.cast_rays_f32(rays, t_max, &mut distances);
    let faces = rays
        .par_iter()
        .zip(&distances)
        .with_min_len(FACE_PIECE)
        .map(|(r, d)| {
            if d.is_finite() {
                scene
                    .first_hit_f32([r[0], r[1], r[2]], [r[3], r[4], r[5]], t_max)
                    .map_or(MISS_FACE, |(_, face)| i64::from(face))
            } else {
                MISS_FACE
            }
        })
        .collect();
    (distances, faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_unit_ray_is_packed_in_f32() {
        let rays = ray_records(&[1.0, 2.0, 3.0], &[0.0, 0.6, 0.8]).unwrap();
        assert_eq!(rays, vec![[1.0, 2.0, 3.0, 0.0, 0.6, 0.8]]);
    }

    #[test]
    fn bad_rays_are_named() {
        let nan = ray_records(
            &[0.0, 0.0, 0.0, f64::NAN, 0.0, 0.0],
            &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0],
        );
        assert!(nan.unwrap_err().starts_with("origins[1] is (NaN, 0, 0)"));
        let zero = ray_records(&[0.0; 3], &[0.0; 3]).unwrap_err();
        assert!(zero.contains("zero-length"), "{zero}");
        let long = ray_records(&[0.0; 3], &[0.0, 0.0, 2.0]).unwrap_err();
        assert!(long.contains("of length 2"), "{long}");
        let far = ray_records(&[1e300, 0.0, 0.0], &[0.0, 0.0, 1.0]).unwrap_err();
        assert!(far.contains("single-precision"), "{far}");
        let count = ray_records(&[0.0; 6], &[0.0, 0.0, 1.0]).unwrap_err();
        assert!(count.contains("2 rows"), "{count}");
    }

    #[test]
    fn the_range_bound_is_a_distance() {
        assert_eq!(range_bound(f64::INFINITY), Ok(f32::INFINITY));
        assert_eq!(range_bound(2.5), Ok(2.5));
        assert!(range_bound(-1.0).is_err());
        assert!(range_bound(f64::NAN).is_err());
    }

    #[test]
    fn faces_come_with_the_batch_distances() {
        let world = scene::builtin::scene("cube")
            .unwrap()
            .build(std::path::Path::new("."))
            .unwrap();
        let cube = world.as_scene().unwrap();
        // Down onto the top (z = 1), up from inside-below, and away.
        let rays = ray_records(
            &[0.1, 0.2, 3.0, 0.0, 0.0, -2.0, 5.0, 5.0, 5.0],
            &[0.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0],
        )
        .unwrap();
        let (d, f) = cast(cube, &rays, f32::INFINITY);
        assert_eq!(d[0], 2.0);
        assert_eq!(d[1], 2.0);
        assert!(d[2].is_infinite());
        assert_eq!(f[2], MISS_FACE);
        for (k, (face, z)) in f.iter().zip([1.0, 0.0]).enumerate() {
            let t = cube.mesh().triangle(usize::try_from(*face).unwrap());
            assert!([t.a, t.b, t.c].iter().all(|p| p.z == z), "ray {k}: {t:?}");
        }
        // Within a bound: the top at 2 m is out of a 1.5 m reach.
        let (d, f) = cast(cube, &rays[..1], 1.5);
        assert!(d[0].is_infinite() && f[0] == MISS_FACE);
    }
}
