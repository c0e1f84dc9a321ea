//! Files of map segmentation (the algorithm is in [`crate::segment`]).
//!
//! * `SEGMENTS.json`: `{"segments": [[disc index, ...], ...]}`
//!   ([`SegmentsFile`], [`save_segments_json`], [`load_segments_json`]).
//! * `POSES.csv`: header `q1,q2,q3,q4,q5,q6`, then one row per disc, in disc
//!   order, of the manipulator's joint angles in radians for acting on that
//!   disc ([`parse_poses_csv`], [`load_poses_csv`]).
//!
//! ```
//! use map::segment_io::parse_poses_csv;
//!
//! let poses = parse_poses_csv("q1,q2,q3,q4,q5,q6\n0,0.5,1,0,0,-1\n", "POSES.csv")?;
//! assert_eq!(poses, vec![[0.0, 0.5, 1.0, 0.0, 0.0, -1.0]]);
//! let err = parse_poses_csv("q1,q2,q3,q4,q5,q6\n0,0,x,0,0,0\n", "POSES.csv").unwrap_err();
//! assert!(err.to_string().starts_with("POSES.csv:2: field `q3`"), "{err}");
//! # Ok::<(), map::MapError>(())
//! ```

use crate::MapError;
use crate::segment::JointPose;
use crate::sld::DiscId;
use geom::Real;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The segments file: `{"segments": [[disc index, ...], ...]}`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentsFile {
    /// Disc indices of each segment.
    pub segments: Vec<Vec<DiscId>>,
}

/// Write segments as `{"segments": [[...], ...]}` to `path`.
pub fn save_segments_json(path: &Path, segments: &[Vec<DiscId>]) -> Result<(), MapError> {
    let file = SegmentsFile {
        segments: segments.to_vec(),
    };
    let text = serde_json::to_string(&file)
        .map_err(|e| MapError::parse(path.display().to_string(), None, e.to_string()))?;
    std::fs::write(path, text + "\n").map_err(|e| MapError::write(path, e))
}

/// Read a segments file written by [`save_segments_json`].
pub fn load_segments_json(path: &Path) -> Result<Vec<Vec<DiscId>>, MapError> {
    let text = std::fs::read_to_string(path).map_err(|e| MapError::read(path, e))?;
    let file: SegmentsFile = serde_json::from_str(&text)
        .map_err(|e| MapError::parse(path.display().to_string(), Some(e.line()), e.to_string()))?;
    Ok(file.segments)
}

/// The header of pose files.
pub const POSES_CSV_HEADER: [&str; 6] = ["q1", "q2", "q3", "q4", "q5", "q6"];

/// Largest joint angle a poses CSV may hold, radians (4π: two turns either
/// way, past any arm's joint range; issue 48: 1e308 was taken as it was).
pub const MAX_POSE_ANGLE_RAD: Real = 4.0 * std::f64::consts::PI;

/// Parse a poses CSV: header `q1,q2,q3,q4,q5,q6`, then one row of six joint
/// angles in radians per disc, each within [`MAX_POSE_ANGLE_RAD`] (blank
/// lines ignored). Errors name `source_name`, the line and the field.
pub fn parse_poses_csv(text: &str, source_name: &str) -> Result<Vec<JointPose>, MapError> {
    let err = |line: Option<usize>, message: String| MapError::parse(source_name, line, message);
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (h, header) = lines
        .next()
        .ok_or_else(|| err(None, "empty file: expected the header q1,...,q6".into()))?;
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    if names != POSES_CSV_HEADER {
        return Err(err(
            Some(h + 1),
            format!(
                "expected the header q1,q2,q3,q4,q5,q6, found `{}`",
                header.trim()
            ),
        ));
    }
    let mut poses = Vec::new();
    for (i, raw) in lines {
        let fields: Vec<&str> = raw.split(',').map(str::trim).collect();
        if fields.len() != 6 {
            return Err(err(
                Some(i + 1),
                format!("expected 6 joint angles, found {} fields", fields.len()),
            ));
        }
        let mut q = [0.0; 6];
        for (k, s) in fields.iter().enumerate() {
            q[k] = s
                .parse::<Real>()
                .ok()
                .filter(|v| v.is_finite() && v.abs() <= MAX_POSE_ANGLE_RAD)
                .ok_or_else(|| {
                    err(
                        Some(i + 1),
                        format!(
                            "field `q{}`: expected an angle in [−4π, 4π] radians, found `{s}`",
                            k + 1
                        ),
                    )
                })?;
        }
        poses.push(q);
    }
    Ok(poses)
}

/// Read a poses CSV file (see [`parse_poses_csv`]).
pub fn load_poses_csv(path: &Path) -> Result<Vec<JointPose>, MapError> {
    let text = std::fs::read_to_string(path).map_err(|e| MapError::read(path, e))?;
    parse_poses_csv(&text, &path.display().to_string())
}
