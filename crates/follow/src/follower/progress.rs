//! Progress checks (P§3.4.7): every τ steps the follower compares where it
//! is with where it was, and gives up what it cannot reach.

use super::{Follower, Mode, Progress};
use geom::Real;
use robot::JointKind;

impl Follower {
    // ---- P§3.4.7: progress -------------------------------------------------

    pub(super) fn reset_progress(&mut self) {
        self.progress.reset_requested = true;
    }

    pub(super) fn check_progress(&mut self, q: &[Real]) {
        if self.progress.reset_requested || self.progress.stored.len() != q.len() {
            self.progress = Progress {
                counter: 0,
                stored: q.to_vec(),
                reset_requested: false,
            };
            return;
        }
        self.progress.counter += 1;
        if self.progress.counter < self.config.progress_steps {
            return;
        }
        self.progress.counter = 0;
        let kinds = self.robot.joint_kinds();
        let (mut rev, mut pri, mut has_rev, mut has_pri) = (0.0, 0.0, false, false);
        for ((k, a), b) in kinds.iter().zip(q).zip(&self.progress.stored) {
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
        let insufficient = (!has_rev || rev.sqrt() < self.config.ceiling_revolute_rad())
            && (!has_pri || pri.sqrt() < self.config.ceiling_prismatic_m);
        self.progress.stored = q.to_vec();
        if insufficient {
            self.give_up();
        }
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
