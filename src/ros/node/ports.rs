//! The node's topics and services: their resolved names, and the subscriptions, publishers and
//! servers opened on them.

use std::sync::Arc;
use std::time::Duration;

use ros2_client::dds::rustdds::Topic;
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{
    CreateError, Name, Node, Publisher, QosProfile, Server, ServiceMapping, ServiceTypeName,
};

use super::NodeError;
use crate::cloud::CloudInput;
use crate::parameters::NodeSettings;
use crate::ros::messages::{
    Clock, DiagnosticArray, EmpoweredReward, Empowerment, Evaluate, EvaluateBatch,
    EvaluateBatchRequest, EvaluateBatchResponse, EvaluateRequest, EvaluateResponse, LaserScan,
    MarkerArray, Odometry, PointCloud2, PoseStamped, RosMessage, RosService, SpeedLimit,
};
use crate::ros::rcl::args::{NameKind, RosArgs};
use crate::speed_limit::SpeedLimitOutput;

use super::speed_limit::SpeedLimiter;

/// The node's topic and service names, fully qualified after namespace and remapping.
pub(super) struct Names {
    pub(super) odom: String,
    /// The scan input's name (unused while point clouds are read instead).
    pub(super) scan: String,
    /// The point-cloud input's name and how its clouds are read, when `use_point_cloud` is on.
    pub(super) cloud: Option<(String, CloudInput)>,
    pub(super) goal: String,
    pub(super) empowerment: String,
    pub(super) reward: String,
    pub(super) markers: String,
    /// The speed-limit output's name and settings, when `publish_speed_limit` is on.
    pub(super) speed_limit: Option<(String, SpeedLimitOutput)>,
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
        let names = Self {
            odom: topic(&interface.odom_topic)?,
            scan: topic(&interface.scan_topic)?,
            cloud: match &interface.cloud {
                Some(input) => Some((topic(&interface.cloud_topic)?, input.clone())),
                None => None,
            },
            goal: topic(&interface.goal_topic)?,
            empowerment: topic(&interface.empowerment_topic)?,
            reward: topic(&interface.reward_topic)?,
            markers: topic(&interface.markers_topic)?,
            speed_limit: match interface.speed_limit {
                Some(output) => Some((topic(&interface.speed_limit_topic)?, output)),
                None => None,
            },
            diagnostics: topic("/diagnostics")?,
            clock: topic("/clock")?,
            evaluate: service(&interface.evaluate_service)?,
            evaluate_batch: service(&interface.evaluate_batch_service)?,
        };
        names.check_distinct()?;
        Ok(names)
    }

    /// Refuses two of the node's topics, or its two services, on one name (rcl allows it, but
    /// it never works): each of the node's topics has a type of its own, so two of them on one
    /// topic never both match a peer, and an input on one of the node's outputs would read its
    /// own scores. Outputs are listed first, so an input remapped onto an output is named
    /// second.
    fn check_distinct(&self) -> Result<(), NodeError> {
        let speed_limit = self.speed_limit.as_ref();
        let topics: Vec<Port> = [
            Some(Port::output::<Empowerment>(
                &self.empowerment,
                "empowerment",
            )),
            Some(Port::output::<EmpoweredReward>(&self.reward, "reward")),
            Some(Port::output::<MarkerArray>(&self.markers, "markers")),
            speed_limit.map(|(name, _)| Port::output::<SpeedLimit>(name, "speed limit")),
            Some(Port::output::<DiagnosticArray>(
                &self.diagnostics,
                "diagnostics",
            )),
            Some(Port::input::<Odometry>(&self.odom, "odometry")),
            Some(match &self.cloud {
                Some((name, _)) => Port::input::<PointCloud2>(name, "point cloud"),
                None => Port::input::<LaserScan>(&self.scan, "scan"),
            }),
            Some(Port::input::<PoseStamped>(&self.goal, "goal")),
            Some(Port::input::<Clock>(&self.clock, "clock")),
        ]
        .into_iter()
        .flatten()
        .collect();
        for (i, first) in topics.iter().enumerate() {
            if let Some(second) = topics[i + 1..].iter().find(|p| p.name == first.name) {
                return Err(NodeError::SharedName {
                    kind: "topic",
                    name: first.name.to_owned(),
                    first: first.what.clone(),
                    second: second.what.clone(),
                    why: if first.output == second.output {
                        "a topic carries one message type"
                    } else {
                        "the node would read its own output"
                    },
                });
            }
        }
        if self.evaluate == self.evaluate_batch {
            return Err(NodeError::SharedName {
                kind: "service",
                name: self.evaluate.clone(),
                first: format!("the evaluate service ({})", Evaluate::ros_type()),
                second: format!("the evaluate_batch service ({})", EvaluateBatch::ros_type()),
                why: "a service has one type, and its requests would go to either",
            });
        }
        Ok(())
    }
}

/// One of the node's topics, for [`Names::check_distinct`]: its resolved name, what it is to
/// the node (with its type), and whether the node publishes it.
struct Port<'a> {
    name: &'a str,
    what: String,
    output: bool,
}

impl<'a> Port<'a> {
    /// The node publishes `M` on `name`.
    fn output<M: RosMessage>(name: &'a str, role: &str) -> Self {
        Self {
            name,
            what: format!("the {role} publisher ({})", M::ros_type()),
            output: true,
        }
    }

    /// The node subscribes to `M` on `name`.
    fn input<M: RosMessage>(name: &'a str, role: &str) -> Self {
        Self {
            name,
            what: format!("the {role} subscription ({})", M::ros_type()),
            output: false,
        }
    }
}

/// The node's sensor input: scans, or point clouds (`use_point_cloud`) and how to read them.
pub(super) enum SensorInput {
    Scans(ros2_client::Subscription<LaserScan>),
    Clouds(ros2_client::Subscription<PointCloud2>, CloudInput),
}

/// The node's topics and services.
pub(super) struct Ports {
    pub(super) odom: ros2_client::Subscription<Odometry>,
    pub(super) sensor: SensorInput,
    pub(super) goal: ros2_client::Subscription<PoseStamped>,
    pub(super) clock: ros2_client::Subscription<Clock>,
    pub(super) empowerment: Arc<Publisher<Empowerment>>,
    pub(super) reward: Arc<Publisher<EmpoweredReward>>,
    pub(super) markers: Arc<Publisher<MarkerArray>>,
    /// The speed-limit output, when `publish_speed_limit` is on.
    pub(super) speed_limit: Option<Arc<SpeedLimiter>>,
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
        // The services keep every request and every answer until it is taken or acknowledged
        // (keep-all): a burst of requests must not overwrite older ones in the reader, nor a
        // burst of answers drop unacknowledged ones from the writer before they were repaired.
        // The node takes requests off the reader at once into its bounded queue
        // (`super::queue`), so the reader holds only those not yet taken.
        let service_qos = reliable.clone().history(History::KeepAll);
        let odom_topic = topic::<Odometry>(node, &names.odom, &sensor)?;
        let goal_topic = topic::<PoseStamped>(node, &names.goal, &reliable)?;
        let clock_topic = topic::<Clock>(node, &names.clock, &sensor)?;
        let empowerment_topic = topic::<Empowerment>(node, &names.empowerment, &reliable)?;
        let reward_topic = topic::<EmpoweredReward>(node, &names.reward, &reliable)?;
        let markers_topic = topic::<MarkerArray>(node, &names.markers, &reliable)?;
        let diagnostics_topic = topic::<DiagnosticArray>(node, &names.diagnostics, &reliable)?;
        // Nav2's controller server subscribes with rclcpp::QoS(10): reliable, volatile.
        let speed_limit = match &names.speed_limit {
            Some((name, output)) => {
                let speed_limit_topic = topic::<SpeedLimit>(node, name, &reliable)?;
                let publisher = node
                    .create_publisher(&speed_limit_topic, Some(reliable.clone()))
                    .map_err(failed("the speed limit publisher"))?;
                Some(Arc::new(SpeedLimiter::new(*output, publisher)))
            }
            None => None,
        };
        let (evaluate_name, evaluate_type) = service::<Evaluate>(&names.evaluate)?;
        let (batch_name, batch_type) = service::<EvaluateBatch>(&names.evaluate_batch)?;
        Ok(Self {
            odom: node
                .create_subscription(&odom_topic, Some(sensor.clone()))
                .map_err(failed("the odometry subscription"))?,
            sensor: match &names.cloud {
                Some((name, input)) => SensorInput::Clouds(
                    node.create_subscription(
                        &topic::<PointCloud2>(node, name, &sensor)?,
                        Some(sensor.clone()),
                    )
                    .map_err(failed("the point cloud subscription"))?,
                    input.clone(),
                ),
                None => SensorInput::Scans(
                    node.create_subscription(
                        &topic::<LaserScan>(node, &names.scan, &sensor)?,
                        Some(sensor.clone()),
                    )
                    .map_err(failed("the scan subscription"))?,
                ),
            },
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
            speed_limit,
            diagnostics: node
                .create_publisher(&diagnostics_topic, Some(reliable.clone()))
                .map_err(failed("the diagnostics publisher"))?,
            evaluate: node
                .create_server(
                    ServiceMapping::Enhanced,
                    &evaluate_name,
                    &evaluate_type,
                    service_qos.clone(),
                    service_qos.clone(),
                )
                .map_err(failed("the evaluate service"))?,
            evaluate_batch: node
                .create_server(
                    ServiceMapping::Enhanced,
                    &batch_name,
                    &batch_type,
                    service_qos.clone(),
                    service_qos,
                )
                .map_err(failed("the evaluate_batch service"))?,
        })
    }
}

/// The topic `name` of message type `M` (its ROS type name from [`RosMessage`]), with `qos`.
fn topic<M: RosMessage>(node: &Node, name: &str, qos: &QosProfile) -> Result<Topic, NodeError> {
    let parsed = Name::parse(name).map_err(|reason| NodeError::TopicName {
        name: name.to_owned(),
        reason,
    })?;
    node.create_topic(&parsed, M::type_name(), qos)
        .map_err(|reason| NodeError::Topic {
            name: name.to_owned(),
            reason,
        })
}

/// The parsed name `name` of service `S` and its ROS type name (from [`RosService`]).
fn service<S: RosService>(name: &str) -> Result<(Name, ServiceTypeName), NodeError> {
    let parsed = Name::parse(name).map_err(|reason| NodeError::ServiceName {
        name: name.to_owned(),
        reason,
    })?;
    Ok((parsed, S::type_name()))
}

/// An error mapper for creating the named entity.
pub(super) fn failed(what: &'static str) -> impl FnOnce(CreateError) -> NodeError {
    move |reason| NodeError::Create { what, reason }
}
