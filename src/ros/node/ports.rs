//! The node's topics and services: their resolved names, and the subscriptions, publishers and
//! servers opened on them.

use std::sync::Arc;
use std::time::Duration;

use ros2_client::dds::rustdds::Topic;
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{Name, Node, Publisher, QosProfile, Server, ServiceMapping, ServiceTypeName};

use super::NodeError;
use crate::config::NodeSettings;
use crate::ros::args::{NameKind, RosArgs};
use crate::ros::messages::{
    Clock, DiagnosticArray, EmpoweredReward, Empowerment, Evaluate, EvaluateBatch,
    EvaluateBatchRequest, EvaluateBatchResponse, EvaluateRequest, EvaluateResponse, LaserScan,
    MarkerArray, Odometry, PoseStamped, RosMessage, RosService,
};

/// The node's topic and service names, fully qualified after namespace and remapping.
pub(super) struct Names {
    pub(super) odom: String,
    pub(super) scan: String,
    pub(super) goal: String,
    pub(super) empowerment: String,
    pub(super) reward: String,
    pub(super) markers: String,
    pub(super) diagnostics: String,
    pub(super) clock: String,
    pub(super) evaluate: String,
    pub(super) evaluate_batch: String,
}

impl Names {
    /// Resolves the configured names for node `node` in `namespace` by rcl's rules
    /// ([`RosArgs::resolve`]).
    pub(super) fn resolve(
        interface: &NodeSettings,
        args: &RosArgs,
        node: &str,
        namespace: &str,
    ) -> Result<Self, NodeError> {
        let resolve = |name: &str, kind| {
            args.resolve(name, kind, node, namespace)
                .map_err(NodeError::from)
        };
        let topic = |name: &str| resolve(name, NameKind::Topic);
        let service = |name: &str| resolve(name, NameKind::Service);
        Ok(Self {
            odom: topic(&interface.odom_topic)?,
            scan: topic(&interface.scan_topic)?,
            goal: topic(&interface.goal_topic)?,
            empowerment: topic(&interface.empowerment_topic)?,
            reward: topic(&interface.reward_topic)?,
            markers: topic(&interface.markers_topic)?,
            diagnostics: topic("/diagnostics")?,
            clock: topic("/clock")?,
            evaluate: service(&interface.evaluate_service)?,
            evaluate_batch: service(&interface.evaluate_batch_service)?,
        })
    }
}

/// The node's topics and services.
pub(super) struct Ports {
    pub(super) odom: ros2_client::Subscription<Odometry>,
    pub(super) scan: ros2_client::Subscription<LaserScan>,
    pub(super) goal: ros2_client::Subscription<PoseStamped>,
    pub(super) clock: ros2_client::Subscription<Clock>,
    pub(super) empowerment: Arc<Publisher<Empowerment>>,
    pub(super) reward: Arc<Publisher<EmpoweredReward>>,
    pub(super) markers: Arc<Publisher<MarkerArray>>,
    pub(super) diagnostics: Publisher<DiagnosticArray>,
    pub(super) evaluate: Server<EvaluateRequest, EvaluateResponse>,
    pub(super) evaluate_batch: Server<EvaluateBatchRequest, EvaluateBatchResponse>,
}

impl Ports {
    pub(super) fn open(node: &mut Node, names: &Names) -> Result<Self, NodeError> {
        let reliable = QosProfile::publisher_default()
            .reliability_reliable(WhenFull::Wait(Duration::from_millis(10)))
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 10 });
        // REP 2003 sensor data: best effort, small queue; matches reliable publishers too.
        let sensor = QosProfile::subscription_default()
            .reliability_best_effort()
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 5 });
        let odom_topic = topic::<Odometry>(node, &names.odom, &sensor)?;
        let scan_topic = topic::<LaserScan>(node, &names.scan, &sensor)?;
        let goal_topic = topic::<PoseStamped>(node, &names.goal, &reliable)?;
        let clock_topic = topic::<Clock>(node, &names.clock, &sensor)?;
        let empowerment_topic = topic::<Empowerment>(node, &names.empowerment, &reliable)?;
        let reward_topic = topic::<EmpoweredReward>(node, &names.reward, &reliable)?;
        let markers_topic = topic::<MarkerArray>(node, &names.markers, &reliable)?;
        let diagnostics_topic = topic::<DiagnosticArray>(node, &names.diagnostics, &reliable)?;
        let (evaluate_name, evaluate_type) = service::<Evaluate>(&names.evaluate)?;
        let (batch_name, batch_type) = service::<EvaluateBatch>(&names.evaluate_batch)?;
        Ok(Self {
            odom: node
                .create_subscription(&odom_topic, Some(sensor.clone()))
                .map_err(failed("the odometry subscription"))?,
            scan: node
                .create_subscription(&scan_topic, Some(sensor.clone()))
                .map_err(failed("the scan subscription"))?,
            clock: node
                .create_subscription(&clock_topic, Some(sensor.clone()))
                .map_err(failed("the /clock subscription"))?,
            goal: node
                .create_subscription(&goal_topic, Some(reliable.clone()))
                .map_err(failed("the goal subscription"))?,
            empowerment: Arc::new(
                node.create_publisher(&empowerment_topic, Some(reliable.clone()))
                    .map_err(failed("the empowerment publisher"))?,
            ),
            reward: Arc::new(
                node.create_publisher(&reward_topic, Some(reliable.clone()))
                    .map_err(failed("the reward publisher"))?,
            ),
            markers: Arc::new(
                node.create_publisher(&markers_topic, Some(reliable.clone()))
                    .map_err(failed("the markers publisher"))?,
            ),
            diagnostics: node
                .create_publisher(&diagnostics_topic, Some(reliable.clone()))
                .map_err(failed("the diagnostics publisher"))?,
            evaluate: node
                .create_server(
                    ServiceMapping::Enhanced,
                    &evaluate_name,
                    &evaluate_type,
                    reliable.clone(),
                    reliable.clone(),
                )
                .map_err(failed("the evaluate service"))?,
            evaluate_batch: node
                .create_server(
                    ServiceMapping::Enhanced,
                    &batch_name,
                    &batch_type,
                    reliable.clone(),
                    reliable,
                )
                .map_err(failed("the evaluate_batch service"))?,
        })
    }
}

/// The topic `name` of message type `M` (its ROS type name from [`RosMessage`]), with `qos`.
fn topic<M: RosMessage>(node: &Node, name: &str, qos: &QosProfile) -> Result<Topic, NodeError> {
    let parsed = Name::parse(name).map_err(|e| NodeError::TopicName {
        name: name.to_owned(),
        reason: format!("{e:?}"),
    })?;
    node.create_topic(&parsed, M::type_name(), qos)
        .map_err(|e| NodeError::Topic {
            name: name.to_owned(),
            reason: format!("{e:?}"),
        })
}

/// The parsed name `name` of service `S` and its ROS type name (from [`RosService`]).
fn service<S: RosService>(name: &str) -> Result<(Name, ServiceTypeName), NodeError> {
    let parsed = Name::parse(name).map_err(|e| NodeError::ServiceName {
        name: name.to_owned(),
        reason: format!("{e:?}"),
    })?;
    Ok((parsed, S::type_name()))
}

/// An error mapper for creating the named entity.
pub(super) fn failed<E: std::fmt::Debug>(what: &'static str) -> impl FnOnce(E) -> NodeError {
    move |e| NodeError::Create {
        what,
        reason: format!("{e:?}"),
    }
}
