//! The map products of Stage One (A§5.2–5.3): the TSDF mesh's Scale-Like
//! Discs, each tied to the viewpoint that saw it, and their segments; with
//! the material belief of each disc once materials are identified.

use crate::judge::Judge;
use crate::{ExploreError, MappingConfig};
use geom::{Real, TriMesh, Vector3};
use record::ViewpointRecord;
use sensor::SweepPoint;

/// Scale-Like Discs of the TSDF mesh (A§5.2, Table 6.1: μ = 0.04 m, n_min =
/// 8), each with the viewpoint that saw it (the viewpoint of the nearest
/// measured point) and its segment (A§5.3, with the pose graph τq over those
/// viewpoints' joints).
#[derive(Clone, Debug, Default)]
pub struct DiscMap {
    /// The discs.
    pub discs: Vec<map::Disc>,
    /// Per disc: the viewpoint (index into `viewpoints`) that saw it.
    pub viewpoint: Vec<usize>,
    /// Per disc: its unit normal turned toward the scanner of its nearest
    /// measured point (the side of the surface that was seen).
    pub facing: Vec<Vector3>,
    /// Per disc: its segment (into `segments`).
    pub segment: Vec<map::SegmentId>,
    /// The segments: disc indices, ascending.
    pub segments: Vec<Vec<map::DiscId>>,
    /// Per disc: the material of the nearest true surface (index into the
    /// material table; runs with a ground truth, [`Judge::true_material`]).
    pub true_material: Vec<Option<usize>>,
    /// The scene's material names.
    pub material_names: Vec<String>,
    /// Per disc: the material posterior (one probability per material of
    /// the scene, uniform until an LRC observation updates it; empty for
    /// worlds without materials).
    pub posterior: Vec<Vec<Real>>,
    /// Per disc: the material information remaining `H3` (eq. 4.16, summed
    /// over the disc's voxels).
    pub h3: Vec<Real>,
    /// Per disc: LRC observations that updated it.
    pub observations: Vec<usize>,
    /// Per disc: the viewpoint (`k`) since which its most probable material
    /// has had `p ≥ 0.8` ([`crate::lrc::IDENTIFIED_P`]), `None` while it has
    /// not; empty for worlds without materials.
    pub identified_at: Vec<Option<usize>>,
    /// `H3` over every disc voxel (eq. 4.17; a voxel shared by two discs
    /// counts once), when materials were identified.
    pub h3_total: Option<Real>,
}

impl DiscMap {
    /// The share of the discs with at least one LRC observation and a known
    /// true material whose most probable material is the true one (`None`
    /// without such discs).
    pub fn material_accuracy(&self) -> Option<Real> {
        let mut n = 0usize;
        let mut right = 0usize;
        for ((p, t), o) in self
            .posterior
            .iter()
            .zip(&self.true_material)
            .zip(&self.observations)
        {
            let (Some(t), true) = (t, *o > 0) else {
                continue;
            };
            n += 1;
            let best = p
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))
                .map(|(i, _)| i);
            right += usize::from(best == Some(*t));
        }
        (n > 0).then(|| right as Real / n as Real)
    }
}

impl DiscMap {
    /// The discs as `discs.csv` holds them.
    pub fn table(&self) -> record::DiscTable {
        let n = self.discs.len();
        record::DiscTable {
            discs: self
                .discs
                .iter()
                .map(|d| record::DiscRecord {
                    centre: d.centre,
                    normal: d.normal,
                    radius_m: d.radius_m,
                    points: d.points,
                })
                .collect(),
            segment: self.segment.iter().map(|s| s.0).collect(),
            viewpoint: self.viewpoint.clone(),
            true_material: self.true_material.clone(),
            material_names: self.material_names.clone(),
            posterior: (self.posterior.len() == n).then(|| self.posterior.clone()),
            h3: (self.h3.len() == n).then(|| (self.h3.clone(), self.observations.clone())),
            identified_at: (self.identified_at.len() == n).then(|| self.identified_at.clone()),
        }
    }

    /// The segments as `segments.json` holds them.
    pub fn segments_file(&self) -> record::explore::SegmentsFile {
        record::explore::SegmentsFile {
            segments: self
                .segments
                .iter()
                .map(|s| s.iter().map(|d| d.0).collect())
                .collect(),
        }
    }
}

/// Discs of `mesh`, each tied to the viewpoint of the nearest point of
/// `cloud`, and segmented with those viewpoints' joints as the pose graph.
pub(crate) fn disc_map(
    mesh: &TriMesh,
    (cloud, cloud_viewpoint): (&[SweepPoint], &[usize]),
    viewpoints: &[ViewpointRecord],
    (materials, judge): (&[scene::Material], &dyn Judge),
    mapping: &MappingConfig,
    seed: u64,
) -> Result<DiscMap, ExploreError> {
    use kiddo::{ImmutableKdTree, SquaredEuclidean};
    if mesh.vertices.is_empty() || cloud.is_empty() {
        return Ok(DiscMap::default());
    }
    let normals = mesh.vertex_normals();
    let sld = map::generate_discs(
        &mesh.vertices,
        map::Orientation::ReferenceNormals(&normals),
        &mapping.sld,
        seed,
    )?;
    let pts: Vec<[Real; 3]> = cloud
        .iter()
        .map(|p| [p.point.x, p.point.y, p.point.z])
        .collect();
    let tree: ImmutableKdTree<Real, 3> = ImmutableKdTree::new_from_slice(&pts);
    // Per disc, its nearest measured point: its viewpoint, and the side
    // its scanner saw the disc from.
    let nearest: Vec<usize> = sld
        .discs
        .iter()
        .map(|d| {
            tree.approx_nearest_one::<SquaredEuclidean>(&[d.centre.x, d.centre.y, d.centre.z])
                .item as usize
        })
        .collect();
    let viewpoint: Vec<usize> = nearest.iter().map(|&n| cloud_viewpoint[n]).collect();
    let poses: Vec<map::segment::JointPose> = viewpoint
        .iter()
        .map(|&k| {
            let mut pose = [0.0; 6];
            for (slot, v) in pose.iter_mut().zip(&viewpoints[k].joints) {
                *slot = *v;
            }
            pose
        })
        .collect();
    let dof6 = viewpoints.first().is_some_and(|r| r.joints.len() == 6);
    let segments = map::segment_discs(
        &sld.discs,
        dof6.then_some(poses.as_slice()),
        &mapping.segment,
    )?;
    let mut segment = vec![map::SegmentId(0); sld.discs.len()];
    for (s, members) in segments.iter().enumerate() {
        for d in members {
            segment[d.0] = map::SegmentId(s);
        }
    }
    let facing: Vec<Vector3> = sld
        .discs
        .iter()
        .zip(&nearest)
        .map(|(d, &n)| {
            let normal = d.normal.into_inner();
            if normal.dot(&(cloud[n].origin - d.centre)) < 0.0 {
                -normal
            } else {
                normal
            }
        })
        .collect();
    let true_material = sld
        .discs
        .iter()
        .zip(&facing)
        .map(|(d, f)| judge.true_material(&d.centre, f))
        .collect();
    let material_names = materials.iter().map(|m| m.name.clone()).collect();
    Ok(DiscMap {
        discs: sld.discs,
        viewpoint,
        segment,
        segments,
        true_material,
        facing,
        material_names,
        ..DiscMap::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom::{Point3, UnitVector3, Vector3};

    /// `discs.csv` of a run starts with the disc-file contract of
    /// `map::sld_io`, value for value: the same discs give the same columns.
    #[test]
    fn the_run_table_extends_map_s_disc_file() {
        let discs = vec![
            map::Disc {
                centre: Point3::new(0.1, -0.25, 1.52),
                normal: UnitVector3::new_normalize(Vector3::new(0.1, 0.2, -0.97)),
                radius_m: 0.04,
                points: 11,
            },
            map::Disc {
                centre: Point3::new(-0.7, 0.75, 1.0),
                normal: -Vector3::y_axis(),
                radius_m: 0.04,
                points: 8,
            },
        ];
        let d = DiscMap {
            discs: discs.clone(),
            viewpoint: vec![0, 3],
            segment: vec![map::SegmentId(0), map::SegmentId(1)],
            segments: vec![vec![map::DiscId(0)], vec![map::DiscId(1)]],
            true_material: vec![Some(1), None],
            material_names: vec!["painted_metal".into(), "timber".into()],
            posterior: vec![vec![0.5, 0.5], vec![0.1, 0.9]],
            h3: vec![0.69, 0.33],
            observations: vec![0, 2],
            h3_total: Some(1.02),
            ..DiscMap::default()
        };
        let run = d.table().to_csv().unwrap();
        let mut contract = Vec::new();
        map::sld_io::write_discs_csv(&mut contract, &discs, &[]).unwrap();
        let contract = String::from_utf8(contract).unwrap();
        for (a, b) in run.lines().zip(contract.lines()) {
            assert!(a.starts_with(b), "{a} / {b}");
            assert_eq!(a.as_bytes().get(b.len()), Some(&b','));
        }
        let read = map::sld_io::parse_discs_csv(&run, "discs.csv").unwrap();
        for (r, d) in read.iter().zip(&discs) {
            assert_eq!(
                (r.centre, r.radius_m, r.points),
                (d.centre, d.radius_m, d.points)
            );
            assert!((r.normal.into_inner() - d.normal.into_inner()).norm() < 1e-15);
        }
        assert_eq!(
            d.segments_file().to_json().unwrap(),
            "{\"segments\":[[0],[1]]}\n"
        );
    }
}
