//! An exploration's viewpoints: [`ViewpointRecord`] per viewpoint, and the
//! three tables made of them, `viewpoints.csv`, `candidates.csv` and
//! `path.csv`, written and read back here.

use crate::RecordError;
use crate::table::Table;
use geom::Real;
use robot::timing::RobotTime;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// One viewpoint of an exploration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewpointRecord {
    /// 0 for the start pose's sweep.
    pub k: usize,
    /// 1 (Stage One) or 2 (Stage Two).
    pub stage: u8,
    /// Joints at the viewpoint.
    pub joints: Vec<Real>,
    /// `[f1, f2, f3, f4]` of the chosen candidate (`None` at the start).
    pub f: Option<[Real; 4]>,
    /// Stage Two: the disc aimed at (index into the disc map).
    pub target_disc: Option<usize>,
    /// `H3` over every disc voxel after the viewpoint (eq. 4.17): every Stage
    /// Two row, and Stage One's last, once Stage One's sweeps are classified
    /// on its map (Stage Two's baseline); `None` on the other rows.
    pub h3: Option<Real>,
    /// Discs whose most probable material has `p ≥ 0.8` after the
    /// viewpoint, on the rows that hold `h3` (`None` on the others).
    #[serde(default)]
    pub discs_identified: Option<usize>,
    /// Unweighted H1 (eq. 4.10) after the sweep.
    pub h1: Real,
    /// Weighted H1 (eq. 4.11) after the sweep.
    pub h1_weighted: Real,
    /// H2 (eq. 4.14) after the sweep.
    pub h2: Real,
    /// Weighted H1 the decision predicted would remain (f1).
    pub predicted_h1_weighted: Option<Real>,
    /// Safe candidates scored (Stage One), or discs ranked (Stage Two).
    pub candidates: usize,
    /// Size of the Pareto front.
    pub front: usize,
    /// Chosen candidates without a safe path.
    pub unreachable: usize,
    /// Unknown voxels the sweep was predicted to reveal.
    pub predicted_revealed: usize,
    /// Voxels the sweep actually made known.
    pub revealed: u64,
    /// Share of the true surfaces in A1 covered by the points so far (runs
    /// judged against a ground truth).
    pub coverage_a1: Option<Real>,
    /// Σ|Δq| of the motion to the viewpoint, radians.
    pub joint_travel: Real,
    /// Waypoints of the motion (2 for a direct one).
    pub waypoints: usize,
    /// The motion's waypoints (joints), from the previous viewpoint's pose
    /// to this one's (empty at the start).
    #[serde(default)]
    pub path: Vec<Vec<Real>>,
    /// Stage One: `[f1, f2, f3, f4]` of every candidate the decision scored,
    /// in its order, and whether it was on the first Pareto front (Fig. 6.6).
    #[serde(default)]
    pub scored: Vec<ScoredCandidate>,
    /// Wall times, ms (0 when timings are off).
    pub decision_ms: Real,
    /// Choice and path planning, ms.
    pub plan_ms: Real,
    /// Sweep (scanning), ms.
    pub sweep_ms: Real,
    /// Integration into the planning grid and the TSDF, ms.
    pub integrate_ms: Real,
    /// The robot time since the previous viewpoint (its decision, the
    /// motion here and the sweep; the first viewpoint's from the start),
    /// by the robot clock (`hw::clock`); the rows add up to `run.json`'s
    /// `robot_time_s`.
    #[serde(default)]
    pub robot_time: RobotTime,
}

/// One candidate of a Stage One decision, as scored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScoredCandidate {
    /// `[f1, f2, f3, f4]`.
    pub f: [Real; 4],
    /// On the Pareto front of the decision's first choice.
    pub front: bool,
}

/// A configuration found unsafe along an executed motion.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UnsafeConfiguration {
    /// Viewpoint whose motion or sweep it was on.
    pub viewpoint: usize,
    /// The joints.
    pub joints: Vec<Real>,
    /// Its `dist(Q)` against the map of that moment.
    pub dist: Real,
}

/// The file of the viewpoints' rows.
pub const VIEWPOINTS_CSV: &str = "viewpoints.csv";
/// The file of every scored candidate.
pub const CANDIDATES_CSV: &str = "candidates.csv";
/// The file of the executed motions' waypoints.
pub const PATH_CSV: &str = "path.csv";

/// `viewpoints.csv`: one row per viewpoint (`k, stage, q1..qn, f1..f4, h1,
/// h1_weighted, h2, h3, predicted_h1_weighted, actual_h1_weighted,
/// candidates, front, unreachable, predicted_revealed, revealed,
/// coverage_a1, joint_travel, waypoints, decision_ms, plan_ms, sweep_ms,
/// integrate_ms, target_disc, discs_identified, robot_time_s,
/// robot_moving_while_scanning_s, robot_moving_s, robot_standing_to_sweep_s,
/// robot_deciding_s`); empty cells for no value.
pub fn viewpoints_csv(viewpoints: &[ViewpointRecord]) -> String {
    let dof = viewpoints.first().map_or(0, |r| r.joints.len());
    let mut out = String::from("k,stage");
    for j in 1..=dof {
        let _ = write!(out, ",q{j}");
    }
    out.push_str(
        ",f1,f2,f3,f4,h1,h1_weighted,h2,h3,predicted_h1_weighted,actual_h1_weighted,\
         candidates,front,unreachable,predicted_revealed,revealed,coverage_a1,joint_travel,waypoints,\
         decision_ms,plan_ms,sweep_ms,integrate_ms,target_disc,discs_identified,robot_time_s,\
         robot_moving_while_scanning_s,robot_moving_s,robot_standing_to_sweep_s,robot_deciding_s\n",
    );
    let opt = |v: Option<Real>| v.map_or(String::new(), |x| format!("{x}"));
    for r in viewpoints {
        let _ = write!(out, "{},{}", r.k, r.stage);
        for v in &r.joints {
            let _ = write!(out, ",{v}");
        }
        let f = r.f.map_or([None; 4], |f| f.map(Some));
        for v in f {
            let _ = write!(out, ",{}", opt(v));
        }
        let _ = writeln!(
            out,
            ",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.3},{:.3},{:.3},{:.3},{},{},{:.6},{:.6},{:.6},{:.6},{:.6}",
            r.h1,
            r.h1_weighted,
            r.h2,
            opt(r.h3),
            opt(r.predicted_h1_weighted),
            r.h1_weighted,
            r.candidates,
            r.front,
            r.unreachable,
            r.predicted_revealed,
            r.revealed,
            opt(r.coverage_a1),
            r.joint_travel,
            r.waypoints,
            r.decision_ms,
            r.plan_ms,
            r.sweep_ms,
            r.integrate_ms,
            r.target_disc.map_or(String::new(), |t| t.to_string()),
            r.discs_identified.map_or(String::new(), |t| t.to_string()),
            r.robot_time.total_s(),
            r.robot_time.moving_while_scanning_s,
            r.robot_time.moving_s,
            r.robot_time.standing_to_sweep_s,
            r.robot_time.deciding_s,
        );
    }
    out
}

/// `candidates.csv`: every candidate each Stage One decision scored (k is
/// the viewpoint the decision chose), with `[f1, f2, f3, f4]`, whether it
/// was on the Pareto front and whether it was chosen (Paul Fig. 6.6).
pub fn candidates_csv(viewpoints: &[ViewpointRecord]) -> String {
    let mut out = String::from("k,candidate,f1,f2,f3,f4,front,chosen\n");
    for r in viewpoints {
        for (i, c) in r.scored.iter().enumerate() {
            let [f1, f2, f3, f4] = c.f;
            let _ = writeln!(
                out,
                "{},{i},{f1},{f2},{f3},{f4},{},{}",
                r.k,
                u8::from(c.front),
                u8::from(r.f == Some(c.f))
            );
        }
    }
    out
}

/// `path.csv`: the executed motions, one row per waypoint (k is the
/// viewpoint the motion reached; the start pose is k 0's only row).
pub fn path_csv(viewpoints: &[ViewpointRecord]) -> String {
    let dof = viewpoints.first().map_or(0, |r| r.joints.len());
    let mut out = String::from("k,stage,waypoint");
    for j in 1..=dof {
        let _ = write!(out, ",q{j}");
    }
    out.push('\n');
    for r in viewpoints {
        let start = [r.joints.clone()];
        let rows = if r.path.is_empty() {
            &start[..]
        } else {
            &r.path[..]
        };
        for (i, q) in rows.iter().enumerate() {
            let _ = write!(out, "{},{},{i}", r.k, r.stage);
            for v in q {
                let _ = write!(out, ",{v}");
            }
            out.push('\n');
        }
    }
    out
}

/// The joint columns `q1..q{dof}` of `table`, each required, as one vector
/// per row; `dof` is the number of `q` columns in the header.
pub fn joint_columns(table: &Table) -> Result<Vec<Vec<Real>>, RecordError> {
    let dof = (1..=table.width())
        .take_while(|j| table.has(&format!("q{j}")))
        .count();
    let columns = (1..=dof)
        .map(|j| table.numbers(&format!("q{j}")))
        .collect::<Result<Vec<_>, _>>()?;
    Ok((0..table.len())
        .map(|i| columns.iter().map(|c| c[i]).collect())
        .collect())
}

/// Read the viewpoints back from `viewpoints.csv`, `candidates.csv` and
/// `path.csv` in `dir`. The wall times come back as written (to the
/// microsecond), the robot times to the microsecond; everything else as
/// recorded.
pub fn read_viewpoints(dir: &Path) -> Result<Vec<ViewpointRecord>, RecordError> {
    let vp = Table::read(&dir.join(VIEWPOINTS_CSV))?;
    let k = vp.indices("k")?;
    let stage = vp.indices("stage")?;
    let joints = joint_columns(&vp)?;
    let f: Vec<Vec<Option<Real>>> = ["f1", "f2", "f3", "f4"]
        .iter()
        .map(|n| vp.optional(n))
        .collect::<Result<_, _>>()?;
    let num = |n: &str| vp.numbers(n);
    let idx = |n: &str| vp.indices(n);
    let (h1, h1w, h2) = (num("h1")?, num("h1_weighted")?, num("h2")?);
    let (h3, predicted, coverage) = (
        vp.optional("h3")?,
        vp.optional("predicted_h1_weighted")?,
        vp.optional("coverage_a1")?,
    );
    let (candidates, front, unreachable) = (idx("candidates")?, idx("front")?, idx("unreachable")?);
    let (predicted_revealed, revealed) = (idx("predicted_revealed")?, idx("revealed")?);
    let (travel, waypoints) = (num("joint_travel")?, idx("waypoints")?);
    let times = [
        num("decision_ms")?,
        num("plan_ms")?,
        num("sweep_ms")?,
        num("integrate_ms")?,
    ];
    let target = vp.optional_indices("target_disc")?;
    // Runs written before the column existed have none.
    let identified = if vp.has("discs_identified") {
        vp.optional_indices("discs_identified")?
    } else {
        vec![None; vp.len()]
    };
    // Runs written before the robot clock have no robot time.
    let robot_time = if vp.has("robot_time_s") {
        [
            num("robot_moving_while_scanning_s")?,
            num("robot_moving_s")?,
            num("robot_standing_to_sweep_s")?,
            num("robot_deciding_s")?,
        ]
    } else {
        std::array::from_fn(|_| vec![0.0; vp.len()])
    };
    let mut out = Vec::with_capacity(vp.len());
    for i in 0..vp.len() {
        let stage_i = u8::try_from(stage[i]).ok().filter(|s| (1..=2).contains(s));
        let Some(stage_i) = stage_i else {
            return Err(RecordError::Field {
                file: vp.source.clone(),
                line: i + 2,
                field: "stage".into(),
                message: format!("expected 1 or 2, found {}", stage[i]),
            });
        };
        let fi = match (f[0][i], f[1][i], f[2][i], f[3][i]) {
            (Some(a), Some(b), Some(c), Some(d)) => Some([a, b, c, d]),
            _ => None,
        };
        out.push(ViewpointRecord {
            k: k[i],
            stage: stage_i,
            joints: joints[i].clone(),
            f: fi,
            target_disc: target[i],
            h3: h3[i],
            discs_identified: identified[i],
            h1: h1[i],
            h1_weighted: h1w[i],
            h2: h2[i],
            predicted_h1_weighted: predicted[i],
            candidates: candidates[i],
            front: front[i],
            unreachable: unreachable[i],
            predicted_revealed: predicted_revealed[i],
            revealed: revealed[i] as u64,
            coverage_a1: coverage[i],
            joint_travel: travel[i],
            waypoints: waypoints[i],
            path: Vec::new(),
            scored: Vec::new(),
            decision_ms: times[0][i],
            plan_ms: times[1][i],
            sweep_ms: times[2][i],
            integrate_ms: times[3][i],
            robot_time: RobotTime {
                moving_while_scanning_s: robot_time[0][i],
                moving_s: robot_time[1][i],
                standing_to_sweep_s: robot_time[2][i],
                deciding_s: robot_time[3][i],
            },
        });
    }
    let position: std::collections::HashMap<usize, usize> =
        out.iter().enumerate().map(|(i, r)| (r.k, i)).collect();
    let at = |k: usize, file: &str, line: usize| -> Result<usize, RecordError> {
        position.get(&k).copied().ok_or_else(|| RecordError::Field {
            file: file.to_owned(),
            line,
            field: "k".into(),
            message: format!("viewpoint {k} is not in {VIEWPOINTS_CSV}"),
        })
    };
    let cands = Table::read(&dir.join(CANDIDATES_CSV))?;
    let ck = cands.indices("k")?;
    let cf: Vec<Vec<Real>> = ["f1", "f2", "f3", "f4"]
        .iter()
        .map(|n| cands.numbers(n))
        .collect::<Result<_, _>>()?;
    let cfront = cands.indices("front")?;
    let mut placed = Vec::with_capacity(ck.len());
    for (i, &kk) in ck.iter().enumerate() {
        placed.push(at(kk, &cands.source, i + 2)?);
    }
    for (i, v) in placed.into_iter().enumerate() {
        out[v].scored.push(ScoredCandidate {
            f: [cf[0][i], cf[1][i], cf[2][i], cf[3][i]],
            front: cfront[i] != 0,
        });
    }
    // Every Stage One decision's candidates are there: a file cut at a line
    // end would otherwise be drawn short without a word (issue 48).
    for (i, r) in out.iter().enumerate() {
        if r.stage == 1 && r.scored.len() < r.candidates {
            return Err(RecordError::Field {
                file: cands.source.clone(),
                line: cands.len() + 1,
                field: "k".into(),
                message: format!(
                    "viewpoint {} has {} candidate rows, but {VIEWPOINTS_CSV} line {} says its decision scored {} (is the file cut short?)",
                    r.k,
                    r.scored.len(),
                    i + 2,
                    r.candidates
                ),
            });
        }
    }
    let path = Table::read(&dir.join(PATH_CSV))?;
    let pk = path.indices("k")?;
    let pq = joint_columns(&path)?;
    let mut placed = Vec::with_capacity(pk.len());
    for (i, &kk) in pk.iter().enumerate() {
        placed.push(at(kk, &path.source, i + 2)?);
    }
    for (v, q) in placed.into_iter().zip(pq) {
        out[v].path.push(q);
    }
    // A viewpoint reached without a motion (the start) has its pose as the
    // only row.
    for r in &mut out {
        if r.waypoints == 0 && r.path.len() <= 1 {
            r.path.clear();
        }
    }
    Ok(out)
}
