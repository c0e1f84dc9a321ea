//! Rays files (`scene::io::rays`): exact round trip, and every bad record is an
//! error naming the file and the ray.

#![allow(clippy::unwrap_used, reason = "tests fail on any error")]

use scene::SceneError;
use scene::io::rays::{RAY_BYTES, parse_rays, read_rays, write_rays};

#[test]
fn round_trip_is_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rays.bin");
    let rays = scene::fixtures::incoherent_rays(1000, 7);
    write_rays(&path, &rays).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(bytes.len(), 1000 * RAY_BYTES);
    // Independent decoding of one record: ray 999, field dz.
    let at = 999 * 24 + 20;
    assert_eq!(
        f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()),
        rays[999][5]
    );
    assert_eq!(read_rays(&path).unwrap(), rays);
    // An empty file is zero rays.
    write_rays(&path, &[]).unwrap();
    assert_eq!(std::fs::metadata(&path).unwrap().len(), 0);
    assert!(read_rays(&path).unwrap().is_empty());
}

fn encode(rays: &[[f32; 6]]) -> Vec<u8> {
    rays.iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

#[test]
fn bad_records_name_the_file_and_the_ray() {
    let good = [0.5f32, -1.0, 2.0, 0.0, 0.6, 0.8];
    let path = std::path::Path::new("w/rays.bin");
    let msg = |bytes: &[u8]| parse_rays(path, bytes).unwrap_err().to_string();

    let mut bytes = encode(&[good, good]);
    bytes.push(0);
    assert_eq!(
        msg(&bytes),
        "w/rays.bin: 49 bytes is not a whole number of rays (24 bytes each: six little-endian \
         f32): 2 whole rays and 1 bytes left over from byte 48 (file truncated?)"
    );
    let mut nan = good;
    nan[4] = f32::NAN;
    assert_eq!(
        msg(&encode(&[good, good, good, nan])),
        "w/rays.bin: ray 3: dy is NaN (expected a finite number)"
    );
    let mut long = good;
    long[3] = 0.1;
    let e = parse_rays(path, &encode(&[good, good, long])).unwrap_err();
    assert!(matches!(e, SceneError::Ray { index: 2, .. }), "{e:?}");
    // |d|² = 1.01 → |d| = 1.00499 (f32).
    assert_eq!(
        e.to_string(),
        "w/rays.bin: ray 2: direction (0.1, 0.6, 0.8) has length 1.0049876, expected a unit \
         vector"
    );

    // Writing checks every ray first and leaves no file behind.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.bin");
    let e = write_rays(&out, &[good, good, good, good, nan]).unwrap_err();
    assert!(matches!(e, SceneError::Ray { index: 4, .. }), "{e:?}");
    assert!(e.to_string().contains("out.bin: ray 4: dy is NaN"));
    assert!(!out.exists());
}
