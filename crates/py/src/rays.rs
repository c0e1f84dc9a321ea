//! Rays from NumPy rows, cast as `surveyor raycast` casts them.
//!
//! Each ray is checked and packed as a record of the rays file `surveyor
//! raycast` reads (`scene::io::rays`): six `f32`, the origin then a unit
//! direction, under the same rules (finite values; `|‖d‖² − 1|` at most
//! [`DIRECTION_TOLERANCE`] in `f32`). [`cast`] packs the rows piece by piece
//! on the rayon pool and walks each piece as `surveyor raycast` walks its
//! chunks ([`scene::Scene::first_hits`], the chunk walk of
//! [`scene::Scene::cast_rays_f32`], with the face of each hit): the
//! distances are the CLI's bit for bit. Packing, walking and writing the
//! answer happen piece by piece in buffers each thread reuses, so the rays
//! never exist as a second array and a million rays cost the cast and
//! little besides (`bench/raycast_vs_cli.py` compares the two).

use rayon::prelude::*;
use scene::Scene;
use scene::bvh::RayF32;
use scene::io::rays::DIRECTION_TOLERANCE;

/// Face id of a ray that hits nothing.
pub const MISS_FACE: i64 = -1;

/// Rays one rayon task packs, walks and answers (the CLI's chunk).
const PIECE: usize = 1024;

/// `origins` and `directions` (each `3 n` values, row after row) must hold
/// as many rows.
fn same_rows(origins: &[f64], directions: &[f64]) -> Result<(), String> {
    if origins.len() == directions.len() {
        Ok(())
    } else {
        Err(format!(
            "origins has {} rows and directions {}: give one direction per origin",
            origins.len() / 3,
            directions.len() / 3
        ))
    }
}

/// The rays of `origins` and `directions` (each `3 n` values, row after
/// row, numbered from `first`) prepared for the walk in `rays` (its former
/// content replaced); the first bad ray is an error naming it.
fn pack(
    first: usize,
    origins: &[f64],
    directions: &[f64],
    rays: &mut Vec<RayF32>,
) -> Result<(), String> {
    rays.clear();
    rays.reserve(origins.len() / 3);
    let mut good = true;
    // Checked without a branch per ray; a bad ray is looked for only then.
    for (o, d) in origins.chunks_exact(3).zip(directions.chunks_exact(3)) {
        let (origin, dir, ok) = ray_record(o, d);
        good &= ok;
        rays.push(RayF32::new(origin, dir));
    }
    if good {
        return Ok(());
    }
    let bad = origins
        .chunks_exact(3)
        .zip(directions.chunks_exact(3))
        .position(|(o, d)| !ray_record(o, d).2)
        .unwrap_or_default();
    let row = |v: &[f64]| [v[3 * bad], v[3 * bad + 1], v[3 * bad + 2]];
    Err(ray_error(first + bad, row(origins), row(directions)))
}

/// One ray (an origin row and a direction row) as the origin and direction
/// of a rays-file record, and whether it passes the checks (module docs).
/// Always inlined: returned through memory, its floats cost [`pack`] a
/// store-forwarding stall per ray, a fifth of a million-ray cast.
#[expect(
    clippy::inline_always,
    reason = "measured: plain #[inline] leaves a call and a stall per ray"
)]
#[inline(always)]
fn ray_record(o: &[f64], d: &[f64]) -> ([f32; 3], [f32; 3], bool) {
    let origin = [o[0] as f32, o[1] as f32, o[2] as f32];
    let dir = [d[0] as f32, d[1] as f32, d[2] as f32];
    let n2 = dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2];
    // A NaN or infinity, in `f64` or from rounding to `f32`, leaves a value
    // that is not finite; a zero or overflowing direction fails the length.
    let finite = origin
        .iter()
        .chain(&dir)
        .fold(true, |all, v| all & v.is_finite());
    (
        origin,
        dir,
        finite & ((n2 - 1.0).abs() <= DIRECTION_TOLERANCE),
    )
}

/// What is wrong with a ray [`ray_record`] refused.
#[cold]
fn ray_error(i: usize, o: [f64; 3], d: [f64; 3]) -> String {
    let show = |v: [f64; 3]| format!("({}, {}, {})", v[0], v[1], v[2]);
    if o.iter().any(|v| !v.is_finite()) {
        return format!(
            "origins[{i}] is {}: every coordinate must be a finite number (NaN or infinity found)",
            show(o)
        );
    }
    if d.iter().any(|v| !v.is_finite()) {
        return format!(
            "directions[{i}] is {}: every component must be a finite number (NaN or infinity found)",
            show(d)
        );
    }
    if d.iter().all(|v| *v == 0.0) {
        return format!(
            "directions[{i}] is {}: a zero-length direction; each ray needs a unit direction",
            show(d)
        );
    }
    let o32 = o.map(|v| v as f32);
    if o32.iter().any(|v| !v.is_finite()) {
        return format!(
            "origins[{i}] is {}: beyond the single-precision range (±3.4e38) rays are cast in",
            show(o)
        );
    }
    let d32 = d.map(|v| v as f32);
    let n2 = d32[0] * d32[0] + d32[1] * d32[1] + d32[2] * d32[2];
    format!(
        "directions[{i}] is {}, of length {}: expected a unit vector (|‖d‖² − 1| ≤ \
         {DIRECTION_TOLERANCE}; normalise with d / numpy.linalg.norm(d, axis=1, keepdims=True))",
        show(d),
        Into::<f64>::into(n2).sqrt()
    )
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

/// The first hit within `t_max` of every ray of `origins` and `directions`
/// (each `3 n` values, row after row): its distance (`+inf` on a miss) in
/// `f64`, as `surveyor raycast` computes it, and its face ([`MISS_FACE`] on
/// a miss). The first bad ray is an error naming it. Runs on the calling
/// rayon pool (module docs).
pub fn cast(
    scene: &Scene,
    origins: &[f64],
    directions: &[f64],
    t_max: f32,
) -> Result<(Vec<f64>, Vec<i64>), String> {
    same_rows(origins, directions)?;
    let n = origins.len() / 3;
    // Zeroed by the allocator; every slot is written below.
    let mut distances = vec![0f64; n];
    let mut faces = vec![0i64; n];
    let walked = distances
        .par_chunks_mut(PIECE)
        .zip(faces.par_chunks_mut(PIECE))
        .zip(origins.par_chunks(3 * PIECE))
        .zip(directions.par_chunks(3 * PIECE))
        .enumerate()
        .try_for_each_init(
            || (Vec::with_capacity(PIECE), vec![None; PIECE]),
            |(rays, hits), (k, (((distances, faces), o), d))| {
                pack(k * PIECE, o, d, rays)?;
                let hits = &mut hits[..rays.len()];
                scene.first_hits(rays, t_max, hits);
                for ((distance, face), hit) in
                    distances.iter_mut().zip(faces.iter_mut()).zip(&*hits)
                {
                    (*distance, *face) = hit.map_or((f64::INFINITY, MISS_FACE), |(f, t)| {
                        (f64::from(t), i64::from(f))
                    });
                }
                Ok(())
            },
        );
    // Which piece's error comes back is not fixed: the first piece with a
    // bad ray names its first bad ray.
    walked.map_err(|_: String| {
        origins
            .chunks(3 * PIECE)
            .zip(directions.chunks(3 * PIECE))
            .enumerate()
            .find_map(|(k, (o, d))| pack(k * PIECE, o, d, &mut Vec::new()).err())
            .unwrap_or_default()
    })?;
    Ok((distances, faces))
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene::io::rays::RayRecord;

    fn ray_records(origins: &[f64], directions: &[f64]) -> Result<Vec<RayRecord>, String> {
        same_rows(origins, directions)?;
        let mut rays = Vec::new();
        pack(0, origins, directions, &mut rays)?;
        Ok(rays
            .iter()
            .map(|r| {
                let (o, d) = (r.origin, r.dir);
                [o[0], o[1], o[2], d[0], d[1], d[2]]
            })
            .collect())
    }

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
        // Among many rays in many pieces, the first bad one is named.
        let n = 20_000;
        let mut o = vec![0.0; 3 * n];
        let d: Vec<f64> = (0..n).flat_map(|_| [0.0, 0.0, 1.0]).collect();
        o[3 * 15_000] = f64::NAN;
        o[3 * 5_001 + 2] = f64::INFINITY;
        let first = ray_records(&o, &d).unwrap_err();
        assert!(first.starts_with("origins[5001] is (0, 0, inf)"), "{first}");
        let world = scene::builtin::scene("cube")
            .unwrap()
            .build(std::path::Path::new("."))
            .unwrap();
        let cast_first = cast(world.as_scene().unwrap(), &o, &d, 1.0).unwrap_err();
        assert_eq!(cast_first, first);
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
        let origins = [0.1, 0.2, 3.0, 0.0, 0.0, -2.0, 5.0, 5.0, 5.0];
        let directions = [0.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
        let (d, f) = cast(cube, &origins, &directions, f32::INFINITY).unwrap();
        assert_eq!(d.len(), 3);
        assert_eq!(d[0], 2.0);
        assert_eq!(d[1], 2.0);
        assert!(d[2].is_infinite());
        assert_eq!(f[2], MISS_FACE);
        for (k, (face, z)) in f.iter().zip([1.0, 0.0]).enumerate() {
            let t = cube.mesh().triangle(usize::try_from(*face).unwrap());
            assert!([t.a, t.b, t.c].iter().all(|p| p.z == z), "ray {k}: {t:?}");
        }
        // Within a bound: the top at 2 m is out of a 1.5 m reach.
        let (d, f) = cast(cube, &origins[..3], &directions[..3], 1.5).unwrap();
        assert!(d[0].is_infinite() && f[0] == MISS_FACE);
    }
}
