//! What a run builds, published as it goes: a live view for RViz or
//! Foxglove of a run on a ROS 2 robot.

use crate::serve::now_ns;
use crate::{Ros2Error, Ros2Node};
use geom::{Isometry3, Real};
use record::bag::msg::{MarkerArray, PointCloud2, TfMessage};
use record::bag::topics;
use robot::Robot;
use ros2_client::Publisher;
use sensor::SweepPoint;

/// Nanoseconds since the Unix epoch: the stamps of a live view.
pub fn wall_clock_ns() -> u64 {
    now_ns()
}

/// Publishes a run's robot frames, sweeps and markers on the topics
/// `run.mcap` holds them on (`/tf`, `/tf_static`, `/surveyor/sweep`,
/// `/surveyor/viewpoints`, `/surveyor/discs`, `/surveyor/surface_model`),
/// stamped with the wall clock. A message that cannot be sent does not stop
/// the run: the first failure is kept ([`LiveView::first_failure`]).
pub struct LiveView {
    robot: Robot,
    tf: Publisher<TfMessage>,
    sweeps: Publisher<PointCloud2>,
    markers: Vec<(&'static str, Publisher<MarkerArray>)>,
    sent: u64,
    failure: Option<String>,
    // The publishers live as long as their node.
    _node: Ros2Node,
    _tf_static: Publisher<TfMessage>,
}

impl std::fmt::Debug for LiveView {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LiveView")
            .field("sent", &self.sent)
            .field("failure", &self.failure)
            .finish_non_exhaustive()
    }
}

impl LiveView {
    /// The live view of `robot` standing at `world_from_base` on `node`:
    /// publishes the frames that do not move on `/tf_static` (latched).
    pub fn new(
        mut node: Ros2Node,
        robot: &Robot,
        world_from_base: &Isometry3,
    ) -> Result<Self, Ros2Error> {
        let tf_static = node.latched_publisher::<TfMessage>(topics::TF_STATIC)?;
        tf_static
            .publish(record::bag::static_frames(robot, world_from_base))
            .map_err(|e| Ros2Error::Transfer {
                topic: topics::TF_STATIC.to_owned(),
                message: format!("{e:?}"),
            })?;
        let markers = [topics::VIEWPOINTS, topics::DISCS, topics::SURFACE_MODEL]
            .into_iter()
            .map(|t| Ok((t, node.publisher::<MarkerArray>(t)?)))
            .collect::<Result<_, Ros2Error>>()?;
        Ok(Self {
            robot: robot.clone(),
            tf: node.publisher(topics::TF)?,
            sweeps: node.publisher(topics::SWEEP)?,
            markers,
            sent: 0,
            failure: None,
            _node: node,
            _tf_static: tf_static,
        })
    }

    fn sent<E: std::fmt::Debug>(&mut self, topic: &str, result: Result<(), E>) {
        match result {
            Ok(()) => self.sent += 1,
            Err(e) => {
                if self.failure.is_none() {
                    self.failure = Some(format!("{topic}: {e:?}"));
                }
            }
        }
    }

    /// The robot's link frames at joints `q` on `/tf`.
    pub fn frames(&mut self, q: &[Real]) {
        let msg = record::bag::link_frames(now_ns(), &self.robot, q);
        let r = self.tf.publish(msg);
        self.sent(topics::TF, r);
    }

    /// A sweep's points as one `PointCloud2` on `/surveyor/sweep`.
    pub fn sweep<'a>(&mut self, points: impl IntoIterator<Item = &'a SweepPoint>) {
        let msg = record::bag::point_cloud(now_ns(), points);
        let r = self.sweeps.publish(msg);
        self.sent(topics::SWEEP, r);
    }

    /// `msg` on `topic`, one of `/surveyor/viewpoints`, `/surveyor/discs`
    /// and `/surveyor/surface_model` (stamp it with [`wall_clock_ns`]).
    pub fn markers(&mut self, topic: &str, msg: MarkerArray) {
        let r = match self.markers.iter().find(|(t, _)| *t == topic) {
            Some((_, p)) => p.publish(msg).map_err(|e| format!("{e:?}")),
            None => Err("not a marker topic of the live view".to_owned()),
        };
        self.sent(topic, r);
    }

    /// Messages sent so far.
    pub fn messages_sent(&self) -> u64 {
        self.sent
    }

    /// The first message that could not be sent, and why.
    pub fn first_failure(&self) -> Option<&str> {
        self.failure.as_deref()
    }
}
