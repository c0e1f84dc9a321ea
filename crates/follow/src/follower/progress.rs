//! Progress checks (P§3.4.7): every τ steps the follower compares where it
//! is with where it was, and gives up what it cannot reach.

use super::{Follower, Mode};
use geom::Real;
use robot::JointKind;

/// How many progress periods (τ steps each) the stall watch spans.
const STALL_CHECKS: u32 = 10;

impl Follower {
    // ---- P§3.4.7: progress -------------------------------------------------

    pub(super) fn reset_progress(&mut self) {
        self.progress.reset_requested = true;
    }

    pub(super) fn check_progress(&mut self, q: &[Real]) {
        if self.stalled(q) {
            self.give_up_or_reposition(q);
            return;
        }
        if self.progress.reset_requested || self.progress.stored.len() != q.len() {
            self.progress.counter = 0;
            self.progress.stored = q.to_vec();
            self.progress.reset_requested = false;
            return;
        }
        self.progress.counter += 1;
        if self.progress.counter < self.config.progress_steps {
            return;
        }
        self.progress.counter = 0;
        let insufficient = self.moved_too_little(q, &self.progress.stored);
        self.progress.stored = q.to_vec();
        if insufficient {
            self.give_up_or_reposition(q);
        } else {
            self.progress.give_ups_in_a_row = 0;
        }
    }

    /// [`Self::give_up`], unless the robot repositions first
    /// (`FollowConfig::reposition_steps`, our addition to P§3.4.7): a
    /// redundant robot with a joint in the outer tenth of its range spends
    /// that many steps with the joint-limit term raised to `reposition_gain`
    /// instead of giving its goal up (in any mode), and no new repositioning
    /// starts until twice that many steps after it ended. With
    /// `reposition_after_give_ups` = n it first gives up n − 1 goals in a
    /// row without having moved, and with `reposition_joints_near_limit` =
    /// k it needs k joints in the outer tenth of their ranges.
    fn give_up_or_reposition(&mut self, q: &[Real]) {
        self.progress.give_ups_in_a_row = self.progress.give_ups_in_a_row.saturating_add(1);
        if self.config.reposition_steps > 0
            && self.robot.dof() > 3
            && self.progress.give_ups_in_a_row >= self.config.reposition_after_give_ups
            && self.progress.reposition_left == 0
            && self.joints_near_limit(q)
                >= usize::try_from(self.config.reposition_joints_near_limit.max(1))
                    .unwrap_or(usize::MAX)
        {
            // Once per goal would not hold: the goal's segment and edge are
            // re-created by most updates (arm4 on block2 gave up a new
            // segment id every 11 steps, its yaw and wrist roll on ±π).
            let fresh = self.steps >= self.progress.reposition_after;
            if fresh {
                self.progress.reposition_left = self.config.reposition_steps;
                self.progress.reposition_after =
                    self.steps + 3 * u64::from(self.config.reposition_steps);
                self.progress.give_ups_in_a_row = 0;
                self.reset_progress();
                return;
            }
        }
        self.give_up();
    }

    /// How many joints with limits lie in the outer tenth of their range.
    fn joints_near_limit(&self, q: &[Real]) -> usize {
        self.robot
            .limits()
            .iter()
            .zip(q)
            .filter(|&(l, &qk)| {
                l.is_some_and(|l| {
                    let half = 0.5 * (l.max - l.min);
                    half > 0.0
                        && half.is_finite()
                        && ((qk - 0.5 * (l.max + l.min)) / half).abs() > 0.9
                })
            })
            .count()
    }

    /// The stall watch (our addition to P§3.4.7): every [`STALL_CHECKS`]
    /// progress periods, whatever the goal did meanwhile, the joints must
    /// have moved as much as one step's ceilings allow. P§3.4.7 restarts
    /// its count whenever the goal changes; a robot standing still beside a
    /// surface it re-senses every step sees its follow edge merged away and
    /// chosen again each step, so the count never reached τ (point3 on the
    /// cylinder's foot stood 72 000 sets at one place).
    fn stalled(&mut self, q: &[Real]) -> bool {
        let p = &mut self.progress;
        if p.watched.len() != q.len() {
            p.watched = q.to_vec();
            p.watch_counter = 0;
            return false;
        }
        p.watch_counter += 1;
        if p.watch_counter < STALL_CHECKS * self.config.progress_steps {
            return false;
        }
        let watched = std::mem::replace(&mut self.progress.watched, q.to_vec());
        self.progress.watch_counter = 0;
        self.moved_too_little(q, &watched)
    }

    /// P§3.4.7's test: the change from `before` to `q` is below the
    /// ceilings γ_r (revolute joints) and γ_p (prismatic ones).
    fn moved_too_little(&self, q: &[Real], before: &[Real]) -> bool {
        let kinds = self.robot.joint_kinds();
        let (mut rev, mut pri, mut has_rev, mut has_pri) = (0.0, 0.0, false, false);
        for ((k, a), b) in kinds.iter().zip(q).zip(before) {
            match k {
                JointKind::Revolute => {
                    rev += (a - b) * (a - b);
                    has_rev = true;
                }
                JointKind::Prismatic => {
                    pri += (a - b) * (a - b);
                    has_pri = true;
                }
                JointKind::Fixed => {}
            }
        }
        (!has_rev || rev.sqrt() < self.config.ceiling_revolute_rad())
            && (!has_pri || pri.sqrt() < self.config.ceiling_prismatic_m)
    }

    /// The give-up actions of P§3.4.7.
    pub(super) fn give_up(&mut self) {
        match self.state.mode {
            Mode::Surface => {
                if let Some(s) = self.state.segment.take() {
                    self.marks.unreachable_segments.insert(s, false);
                }
                self.state.path = None;
            }
            Mode::Segment => {
                if let Some(e) = self.state.edge.take() {
                    self.marks.unreachable_edges.insert(e, false);
                }
            }
            Mode::Edge => self.slice_used(),
            Mode::Point => {
                if let Some(p) = self.state.point.as_mut()
                    && let Some(k) = p.current.take()
                {
                    p.used[k] = true;
                }
            }
            Mode::Gap => {
                if let Some(g) = self.state.gap.as_mut() {
                    g.next += 1;
                    g.sensor = None;
                }
            }
        }
        self.reset_progress();
    }
}

#[cfg(test)]
mod tests {
    use super::super::{FollowConfig, Follower, Mode};
    use geom::{Isometry3, Real};
    use std::f64::consts::PI;
    use surface::{SurfaceConfig, SurfaceModel};

    /// arm4 (six joints, each limited to ±π) with `near` of its joints at
    /// 0.95π (the outer tenth) and the rest at 0.3, in segment following
    /// with no goal (so a give-up changes nothing else), repositioning for
    /// 100 steps after `n` give-ups in a row with `k` joints near a limit.
    fn arm4(n: u32, k: u32, near: usize) -> (Follower, Vec<Real>) {
        let robot = robot::builtin("arm4").expect("arm4");
        let model = SurfaceModel::new(SurfaceConfig::default()).expect("model");
        let config = FollowConfig {
            reposition_steps: 100,
            reposition_after_give_ups: n,
            reposition_joints_near_limit: k,
            ..FollowConfig::default()
        };
        let mut f = Follower::new(robot, Isometry3::identity(), model, config).expect("f");
        f.state.mode = Mode::Segment;
        let q: Vec<Real> = (0..6)
            .map(|j| if j < near { 0.95 * PI } else { 0.3 })
            .collect();
        (f, q)
    }

    /// The call of `check_progress` (counted from 1) at which repositioning
    /// starts, within `calls`; `moved(c)` is the joint values at call `c`.
    fn start_of_repositioning(
        f: &mut Follower,
        calls: usize,
        moved: impl Fn(usize) -> Vec<Real>,
    ) -> Option<usize> {
        (1..=calls).find(|&c| {
            f.check_progress(&moved(c));
            f.progress.reposition_left > 0
        })
    }

    /// When repositioning starts, counted by hand (τ = 10). A robot that
    /// never moves: the first call stores the joints, the progress check
    /// then compares every ten calls and each give-up asks for a fresh start
    /// (one call), so goals are given up at calls 11, 22, 33, 44, 55, …
    /// (the stall watch's first look, at call 101, comes later). With the
    /// defaults (at the first give-up, one joint near a limit) repositioning
    /// starts at call 11; after 3 give-ups in a row at 33, after 5 at 55;
    /// asking for two joints near a limit with one there, never. A robot
    /// that moves between calls 13 and 22 passes the check at 22 (its
    /// joints 0.5 rad from those of call 12), which ends the row of
    /// give-ups: standing still from then on, it gives up at 32, 43 and 54
    /// (the check after a pass needs no fresh start), so the third in a
    /// row comes at 54.
    #[test]
    fn repositioning_waits_for_give_ups_in_a_row_and_joints_near_limits() {
        let cases = [
            (0, 1, 1, Some(11)),
            (3, 1, 1, Some(33)),
            (5, 1, 1, Some(55)),
            (5, 2, 1, None),
            (5, 2, 2, Some(55)),
        ];
        for (n, k, near, want) in cases {
            let (mut f, q) = arm4(n, k, near);
            let got = start_of_repositioning(&mut f, 200, |_| q.clone());
            assert_eq!(got, want, "n {n}, k {k}, {near} near a limit");
        }
        let (mut f, q) = arm4(3, 1, 1);
        let mut moved = q.clone();
        moved[5] += 0.5;
        let got =
            start_of_repositioning(
                &mut f,
                200,
                |c| {
                    if c <= 12 { q.clone() } else { moved.clone() }
                },
            );
        assert_eq!(got, Some(54));
    }
}
