//! Material belief (Paul §4.4): Bayes updates by hand, information remaining.
#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers may panic

use geom::{Point3, Real, UnitVector3, Vector3};
use map::MapError;
use map::key::VoxelKey;
use map::material::{MaterialBelief, MaterialConfig, argmax, bayes_update};
use map::sld::Disc;
use proptest::prelude::*;
use rand::{RngExt, SeedableRng};

fn exact() -> MaterialBelief {
    MaterialBelief::new(MaterialConfig {
        min_likelihood: 0.0,
        ..MaterialConfig::default()
    })
    .unwrap()
}

fn close(a: &[Real], b: &[Real]) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
}

#[test]
fn bayes_updates_match_hand_computation() {
    let mut m = exact();
    let k = VoxelKey::new(3, -2, 150);
    assert!(m.insert_surface(k));
    assert!(!m.insert_surface(k));
    assert!(close(m.probabilities(k).unwrap(), &[0.2; 5]));
    // Step 1: uniform prior × z1 = z1 (normalised).
    let z1 = [0.5, 0.2, 0.1, 0.1, 0.1];
    m.update(k, &z1).unwrap();
    assert!(close(m.probabilities(k).unwrap(), &z1));
    // Step 2: P ∝ z1 · z2 = [0.15, 0.08, 0.01, 0.02, 0.04] / 0.30.
    m.update(k, &[0.3, 0.4, 0.1, 0.2, 0.4]).unwrap();
    let p2 = [0.5, 0.08 / 0.3, 0.01 / 0.3, 0.02 / 0.3, 0.04 / 0.3];
    assert!(
        close(m.probabilities(k).unwrap(), &p2),
        "{:?}",
        m.probabilities(k)
    );
    // Step 3: an unnormalised likelihood is fine (only ratios matter):
    // P ∝ p2 · [1, 2, 0, 0, 1] = [0.5, 0.5333.., 0, 0, 0.1333..] / 1.1666...
    m.update(k, &[1.0, 2.0, 0.0, 0.0, 1.0]).unwrap();
    let raw = [0.5, 0.16 / 0.3, 0.0, 0.0, 0.04 / 0.3];
    let sum: Real = raw.iter().sum();
    let p3: Vec<Real> = raw.iter().map(|v| v / sum).collect();
    assert!(close(m.probabilities(k).unwrap(), &p3));
    assert_eq!(m.map_estimate(k), Some(1));
    // H3 = −Σ p ln p.
    let h: Real = -p3
        .iter()
        .filter(|p| **p > 0.0)
        .map(|p| p * p.ln())
        .sum::<Real>();
    assert!((m.h3_voxel(k).unwrap() - h).abs() < 1e-12);
}

#[test]
fn likelihood_floor_keeps_materials_recoverable() {
    let mut m = MaterialBelief::new(MaterialConfig::default()).unwrap(); // floor 1e-3
    let k = VoxelKey::new(0, 0, 0);
    // One overconfident wrong observation …
    m.update(k, &[1.0, 0.0, 0.0, 0.0, 0.0]).unwrap();
    let p = m.probabilities(k).unwrap();
    let expect = 1e-3 / (1.0 + 4e-3);
    assert!((p[2] - expect).abs() < 1e-15);
    // … is overturned by two right ones.
    for _ in 0..2 {
        m.update(k, &[0.0, 0.0, 1.0, 0.0, 0.0]).unwrap();
    }
    assert_eq!(m.map_estimate(k), Some(2));
}

/// `bayes_update` on a bare belief is the voxel update, bit for bit, and
/// leaves the belief alone when there is no evidence.
#[test]
fn bayes_update_is_the_voxel_update() {
    let mut m = MaterialBelief::new(MaterialConfig::default()).unwrap();
    let k = VoxelKey::new(1, 2, 3);
    let mut p = vec![0.2; 5];
    for z in [[0.7, 0.1, 0.1, 0.05, 0.05], [0.0, 0.9, 0.1, 0.0, 0.0]] {
        m.update(k, &z).unwrap();
        assert!(bayes_update(
            &mut p,
            &z,
            MaterialConfig::default().min_likelihood
        ));
        assert_eq!(m.probabilities(k).unwrap(), p.as_slice());
    }
    let before = p.clone();
    assert!(!bayes_update(&mut p, &[0.0; 5], 0.0));
    assert_eq!(p, before);
}

#[test]
fn h3_falls_under_consistent_observations() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let mut m = MaterialBelief::new(MaterialConfig::default()).unwrap();
    let keys: Vec<VoxelKey> = (0..20).map(|i| VoxelKey::new(i, 0, 0)).collect();
    for &k in &keys {
        m.insert_surface(k);
    }
    let h0 = m.h3_total();
    assert!((h0 - 20.0 * 5f64.ln()).abs() < 1e-9);
    let mut last = h0;
    for _ in 0..15 {
        for &k in &keys {
            // Noisy LRC outputs that favour material 3.
            let mut z: [Real; 5] = std::array::from_fn(|_| rng.random_range(0.0..0.3));
            z[3] += 0.4;
            m.update(k, &z).unwrap();
        }
        let h = m.h3_total();
        assert!(h < last, "H3 rose from {last} to {h}");
        last = h;
    }
    assert!(last < 0.05 * h0);
    assert!(keys.iter().all(|k| m.map_estimate(*k) == Some(3)));
}

#[test]
fn h3_of_discs_and_total_are_sums_of_voxels() {
    let mut m = MaterialBelief::new(MaterialConfig::default()).unwrap();
    let disc = Disc {
        centre: Point3::new(0.105, 0.205, 1.52),
        normal: UnitVector3::new_unchecked(Vector3::new(0.0, 0.0, -1.0)),
        radius_m: 0.04,
        points: 30,
    };
    let voxels = m.disc_voxels(&disc);
    // A horizontal disc of radius 4 cm over 1 cm voxels covers roughly its
    // area, one or two layers thick.
    assert!((40..=200).contains(&voxels.len()), "{}", voxels.len());
    assert!(voxels.windows(2).all(|w| w[0] < w[1]));
    assert!(
        voxels
            .iter()
            .all(|k| disc.distance_to_point(&k.center(0.01)) <= 0.01 * 3f64.sqrt() / 2.0)
    );
    // No beliefs yet: nothing to sum.
    assert_eq!(m.h3_disc(&disc), 0.0);
    m.insert_disc(&disc);
    assert_eq!(m.len(), voxels.len());
    let uniform = voxels.len() as Real * 5f64.ln();
    assert!((m.h3_disc(&disc) - uniform).abs() < 1e-9);
    // Identify half the voxels: per-disc and total H3 are the sums.
    for k in voxels.iter().step_by(2) {
        m.update(*k, &[0.05, 0.05, 0.8, 0.05, 0.05]).unwrap();
    }
    let sum: Real = voxels.iter().map(|k| m.h3_voxel(*k).unwrap()).sum();
    assert!((m.h3_disc(&disc) - sum).abs() < 1e-9);
    assert!((m.h3_total() - sum).abs() < 1e-9);
    assert!(m.h3_disc(&disc) < uniform);
    // A voxel elsewhere counts in the total, not in the disc.
    let far = VoxelKey::new(500, 500, 500);
    m.insert_surface(far);
    assert!((m.h3_total() - sum - 5f64.ln()).abs() < 1e-9);
    assert!((m.h3_disc(&disc) - sum).abs() < 1e-9);
    let p = m.disc_probabilities(&disc).unwrap();
    assert!((p.iter().sum::<Real>() - 1.0).abs() < 1e-12);
    assert_eq!(argmax(&p), 2);
}

#[test]
fn update_points_touches_each_voxel_once() {
    let mut m = exact();
    let pts = [
        Point3::new(0.001, 0.001, 0.001),
        Point3::new(0.009, 0.002, 0.003), // same 1 cm voxel
        Point3::new(0.011, 0.0, 0.0),
    ];
    let z = [0.6, 0.1, 0.1, 0.1, 0.1];
    assert_eq!(m.update_points(&pts, &z).unwrap(), 2);
    assert!(close(m.probabilities(VoxelKey::new(0, 0, 0)).unwrap(), &z));
    assert!(close(m.probabilities(VoxelKey::new(1, 0, 0)).unwrap(), &z));
    // A bad point: nothing changes.
    let bad = [Point3::new(0.5, 0.5, 0.5), Point3::new(f64::NAN, 0.0, 0.0)];
    assert!(matches!(
        m.update_points(&bad, &z),
        Err(MapError::BadPoint { .. })
    ));
    assert_eq!(m.len(), 2);
}

#[test]
fn bad_observations_leave_the_belief_unchanged() {
    let mut m = exact();
    let k = VoxelKey::new(1, 2, 3);
    m.update(k, &[0.0, 0.0, 0.0, 0.5, 0.5]).unwrap();
    let before = m.probabilities(k).unwrap().to_vec();
    assert!(matches!(
        m.update(k, &[0.2; 4]),
        Err(MapError::ObservationLength {
            expected: 5,
            got: 4
        })
    ));
    assert!(matches!(
        m.update(k, &[0.2, 0.2, -0.1, 0.2, 0.2]),
        Err(MapError::ObservationValue { index: 2, .. })
    ));
    assert!(matches!(
        m.update(k, &[0.2, 0.2, 0.2, f64::NAN, 0.2]),
        Err(MapError::ObservationValue { index: 3, .. })
    ));
    // Zero evidence: the observation rules out the only possible materials.
    assert!(matches!(
        m.update(k, &[1.0, 1.0, 1.0, 0.0, 0.0]),
        Err(MapError::NoEvidence { .. })
    ));
    assert_eq!(m.probabilities(k).unwrap(), before.as_slice());
    assert!(m.update(VoxelKey::new(9, 9, 9), &[0.0; 5]).is_err());
    assert!(m.probabilities(VoxelKey::new(9, 9, 9)).is_none());
    for bad in [
        (
            MaterialConfig {
                n_materials: 0,
                ..MaterialConfig::default()
            },
            "n_materials",
            "0",
        ),
        (
            MaterialConfig {
                voxel_m: 0.0,
                ..MaterialConfig::default()
            },
            "voxel_m",
            "0",
        ),
        (
            MaterialConfig {
                min_likelihood: 1.0,
                ..MaterialConfig::default()
            },
            "min_likelihood",
            "1",
        ),
    ] {
        let e = MaterialBelief::new(bad.0).unwrap_err();
        assert!(
            matches!(e, MapError::Config { stage: "material", field, .. } if field == bad.1),
            "{e:?}"
        );
        let msg = e.to_string();
        assert!(
            msg.starts_with(&format!("material config `{}`: expected ", bad.1))
                && msg.ends_with(&format!(", got {}", bad.2)),
            "{msg}"
        );
    }
    let c: MaterialConfig = serde_json::from_str(r#"{"voxel_m": 0.02}"#).unwrap();
    assert_eq!((c.n_materials, c.voxel_m), (5, 0.02));
}

proptest! {
    #[test]
    fn posterior_is_a_distribution_and_h3_is_bounded(
        obs in prop::collection::vec(prop::array::uniform5(0.0f64..1.0), 1..12),
        floor in prop::sample::select(vec![0.0, 1e-3]),
    ) {
        let mut m = MaterialBelief::new(MaterialConfig { min_likelihood: floor, ..MaterialConfig::default() }).unwrap();
        let k = VoxelKey::new(0, 0, 0);
        m.insert_surface(k);
        for z in &obs {
            let before = m.probabilities(k).unwrap().to_vec();
            if m.update(k, z).is_ok() {
                let p = m.probabilities(k).unwrap();
                prop_assert!((p.iter().sum::<Real>() - 1.0).abs() < 1e-9);
                prop_assert!(p.iter().all(|v| *v >= 0.0));
                let h = m.h3_voxel(k).unwrap();
                prop_assert!((-1e-12..=5f64.ln() + 1e-12).contains(&h));
            } else {
                prop_assert_eq!(m.probabilities(k).unwrap(), before.as_slice());
            }
        }
    }
}
