//! A ROS 2 node over RustDDS, restricted to loopback unless told otherwise.

use crate::Ros2Error;
use record::bag::msg::RosMessage;
use ros2_client::dds::rustdds;
use ros2_client::{
    Context, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher, QosProfile,
    Subscription,
    qos::{Durability, History, WhenFull},
};
use serde::de::DeserializeOwned;
use std::net::{IpAddr, Ipv4Addr};

/// How to reach other ROS 2 nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ros2Config {
    /// The DDS domain (ROS 2's `ROS_DOMAIN_ID`, 0–232).
    pub domain_id: u16,
    /// Discover and talk on the loopback interface only (the default: DDS
    /// traffic stays on this machine; a real robot's network needs `false`).
    pub loopback_only: bool,
}

impl Ros2Config {
    /// Domain from `ROS_DOMAIN_ID` (0 when unset), loopback only.
    pub fn from_env() -> Result<Self, Ros2Error> {
        let domain_id = match std::env::var("ROS_DOMAIN_ID") {
            Ok(v) if !v.trim().is_empty() => v
                .trim()
                .parse::<u16>()
                .ok()
                .filter(|d| *d <= 232)
                .ok_or(Ros2Error::DomainId { value: v })?,
            _ => 0,
        };
        Ok(Self {
            domain_id,
            loopback_only: true,
        })
    }
}

/// Messages ROS 2's default QoS keeps.
const DEFAULT_DEPTH: usize = 10;

/// A ROS 2 node: one DDS participant, publishers and subscriptions with
/// ROS 2's default QoS (reliable, volatile, keep last 10).
pub struct Ros2Node {
    node: Node,
    qos: QosProfile,
}

impl std::fmt::Debug for Ros2Node {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Ros2Node").finish_non_exhaustive()
    }
}

fn create(what: &str, e: impl std::fmt::Display) -> Ros2Error {
    Ros2Error::Create {
        what: what.to_owned(),
        message: e.to_string(),
    }
}

/// `pkg/msg/Type` as DDS names it.
fn type_name<M: RosMessage>() -> MessageTypeName {
    let mut parts = M::TYPE.split('/');
    let package = parts.next().unwrap_or_default();
    let name = parts.next_back().unwrap_or_default();
    MessageTypeName::new(package, name)
}

/// A topic `/a/b/c` as namespace `/a/b` and name `c`.
fn topic_name(topic: &str) -> Result<Name, Ros2Error> {
    let (ns, base) = topic.rsplit_once('/').unwrap_or(("", topic));
    let ns = if ns.is_empty() { "/" } else { ns };
    Name::new(ns, base).map_err(|e| create(&format!("topic name {topic}"), format!("{e:?}")))
}

impl Ros2Node {
    /// A node `name` in `config`'s domain.
    pub fn new(name: &str, config: &Ros2Config) -> Result<Self, Ros2Error> {
        let mut builder = rustdds::DomainParticipantBuilder::new(config.domain_id);
        if config.loopback_only {
            builder = builder.with_only_networks([IpAddr::V4(Ipv4Addr::LOCALHOST)]);
        }
        let participant = builder.build().map_err(|e| create("DDS participant", e))?;
        let context =
            Context::from_domain_participant(participant).map_err(|e| create("context", e))?;
        let node_name =
            NodeName::new("/", name).map_err(|e| create("node name", format!("{e:?}")))?;
        let mut node = context
            .new_node(
                node_name,
                NodeOptions::new().start_parameter_services(false),
            )
            .map_err(|e| create("node", e))?;
        // The spinner keeps the node's view of the graph (which publishers
        // and subscriptions match ours); it ends when the node is dropped.
        let spinner = node.spinner().map_err(|e| create("node spinner", e))?;
        std::thread::Builder::new()
            .name(format!("ros2 {name}"))
            .spawn(move || futures::executor::block_on(spinner.spin()))
            .map_err(|e| create("node spinner thread", e))?;
        let qos = QosProfile::publisher_default()
            .reliability_reliable(WhenFull::DEFAULT)
            .durability(Durability::Volatile)
            .history(History::KeepLast {
                depth: DEFAULT_DEPTH,
            });
        Ok(Self { node, qos })
    }

    /// The DDS topic of `M` on `topic` with `qos`.
    fn topic<M: RosMessage>(
        &self,
        topic: &str,
        qos: &QosProfile,
    ) -> Result<rustdds::Topic, Ros2Error> {
        self.node
            .create_topic(&topic_name(topic)?, type_name::<M>(), qos)
            .map_err(|e| create(&format!("topic {topic}"), e))
    }

    /// A publisher of `M` on `topic`.
    pub fn publisher<M: RosMessage>(&mut self, topic: &str) -> Result<Publisher<M>, Ros2Error> {
        let t = self.topic::<M>(topic, &self.qos)?;
        self.node
            .create_publisher::<M>(&t, Some(self.qos.clone()))
            .map_err(|e| create(&format!("publisher on {topic}"), e))
    }

    /// How many publishers match `subscription` (one of this node's).
    pub fn publishers_of<M: 'static>(&self, subscription: &Subscription<M>) -> usize {
        subscription.get_publisher_count(&self.node)
    }

    /// How many subscriptions match `publisher` (one of this node's).
    pub fn subscriptions_of<M: RosMessage>(&self, publisher: &Publisher<M>) -> usize {
        publisher.get_subscription_count(&self.node)
    }

    /// A publisher of `M` on `topic` whose last message late subscribers
    /// get too (transient local, keep last 1: what ROS 2's `/tf_static`
    /// takes).
    pub fn latched_publisher<M: RosMessage>(
        &mut self,
        topic: &str,
    ) -> Result<Publisher<M>, Ros2Error> {
        let qos = self.latched_qos();
        let t = self.topic::<M>(topic, &qos)?;
        self.node
            .create_publisher::<M>(&t, Some(qos))
            .map_err(|e| create(&format!("publisher on {topic}"), e))
    }

    /// A subscription to `M` on `topic` that also gets the last message a
    /// latched publisher sent before it matched ([`Ros2Node::latched_publisher`]).
    pub fn latched_subscription<M: RosMessage + DeserializeOwned + 'static>(
        &mut self,
        topic: &str,
    ) -> Result<Subscription<M>, Ros2Error> {
        let qos = self.latched_qos();
        let t = self.topic::<M>(topic, &qos)?;
        self.node
            .create_subscription::<M>(&t, Some(qos))
            .map_err(|e| create(&format!("subscription to {topic}"), e))
    }

    /// Transient local, keep last 1.
    fn latched_qos(&self) -> QosProfile {
        self.qos
            .clone()
            .durability(Durability::TransientLocal)
            .history(History::KeepLast { depth: 1 })
    }

    /// A publisher of a clock on `topic` with ROS 2's clock QoS (best
    /// effort, keep last 1: a late time is worth nothing).
    pub fn clock_publisher<M: RosMessage>(
        &mut self,
        topic: &str,
    ) -> Result<Publisher<M>, Ros2Error> {
        let qos = Self::clock_qos();
        let t = self.topic::<M>(topic, &qos)?;
        self.node
            .create_publisher::<M>(&t, Some(qos))
            .map_err(|e| create(&format!("publisher on {topic}"), e))
    }

    /// A subscription to a clock on `topic`: best effort, keep last 1, so
    /// that it matches a robot's `/clock` whether published best effort (as
    /// ROS 2's clock publishers are) or reliably.
    pub fn clock_subscription<M: RosMessage + DeserializeOwned + 'static>(
        &mut self,
        topic: &str,
    ) -> Result<Subscription<M>, Ros2Error> {
        let qos = Self::clock_qos();
        let t = self.topic::<M>(topic, &qos)?;
        self.node
            .create_subscription::<M>(&t, Some(qos))
            .map_err(|e| create(&format!("subscription to {topic}"), e))
    }

    /// ROS 2's clock QoS: best effort, volatile, keep last 1.
    fn clock_qos() -> QosProfile {
        QosProfile::publisher_default()
            .reliability_best_effort()
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 1 })
    }

    /// A subscription to `M` on `topic`.
    pub fn subscription<M: RosMessage + DeserializeOwned + 'static>(
        &mut self,
        topic: &str,
    ) -> Result<Subscription<M>, Ros2Error> {
        self.subscription_keeping(topic, DEFAULT_DEPTH)
    }

    /// A subscription to `M` on `topic` that keeps the last `depth`
    /// messages until they are taken (the default QoS keeps 10: a reader
    /// that needs every joint state of a motion while it works on a scan
    /// keeps more).
    pub fn subscription_keeping<M: RosMessage + DeserializeOwned + 'static>(
        &mut self,
        topic: &str,
        depth: usize,
    ) -> Result<Subscription<M>, Ros2Error> {
        let qos = self.qos.clone().history(History::KeepLast { depth });
        let t = self.topic::<M>(topic, &self.qos)?;
        self.node
            .create_subscription::<M>(&t, Some(qos))
            .map_err(|e| create(&format!("subscription to {topic}"), e))
    }
}
