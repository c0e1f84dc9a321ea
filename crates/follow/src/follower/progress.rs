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
        }
    }

    /// [`Self::give_up`], unless the robot repositions first
    /// (`FollowConfig::reposition_steps`, our addition to P§3.4.7): a
    /// redundant robot with a joint in the outer tenth of its range spends
    /// that many steps with the joint-limit term raised to `reposition_gain`
    /// instead of giving its goal up (in any mode), and no new repositioning
    /// starts until twice that many steps after it ended.
    fn give_up_or_reposition(&mut self, q: &[Real]) {
        if self.config.reposition_steps > 0
            && self.robot.dof() > 3
            && self.progress.reposition_left == 0
            && self.joint_near_limit(q)
        {
            // Once per goal would not hold: the goal's segment and edge are
            // re-created by most updates (arm4 on block2 gave up a new
            // segment id every 11 steps, its yaw and wrist roll on ±π).
            let fresh = self.steps >= self.progress.reposition_after;
            if fresh {
                self.progress.reposition_left = self.config.reposition_steps;
                self.progress.reposition_after =
                    self.steps + 3 * u64::from(self.config.reposition_steps);
                self.reset_progress();
                return;
            }
        }
        self.give_up();
    }

    /// `true` when a joint with limits lies in the outer tenth of its range.
    fn joint_near_limit(&self, q: &[Real]) -> bool {
        self.robot.limits().iter().zip(q).any(|(l, &qk)| {
            l.is_some_and(|l| {
                let half = 0.5 * (l.max - l.min);
                half > 0.0 && half.is_finite() && ((qk - 0.5 * (l.max + l.min)) / half).abs() > 0.9
            })
        })
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
