//! The node's topics and services: their resolved names, and the subscriptions, publishers and
//! servers opened on them.

use std::sync::Arc;
use std::time::Duration;

use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{
    MessageTypeName, Name, Node, Publisher, QosProfile, Server, ServiceMapping, ServiceTypeName,
};

use crate::config::NodeSettings;
use crate::ros::args::{NameKind, RosArgs};
use crate::ros::messages::{
    Clock, DiagnosticArray, EmpoweredReward, Empowerment, EvaluateBatchRequest,
    EvaluateBatchResponse, EvaluateRequest, EvaluateResponse, LaserScan, MarkerArray, Odometry,
    PoseStamped,
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
    ) -> Result<Self, String> {
        let topic = |name: &str| args.resolve(name, NameKind::Topic, node, namespace);
        let service = |name: &str| args.resolve(name, NameKind::Service, node, namespace);
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
    pub(super) fn open(node: &mut Node, names: &Names) -> Result<Self, String> {
        let reliable = QosProfile::publisher_default()
            .reliability_reliable(WhenFull::Wait(Duration::from_millis(10)))
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 10 });
        // REP 2003 sensor data: best effort, small queue; matches reliable publishers too.
        let sensor = QosProfile::subscription_default()
            .reliability_best_effort()
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 5 });
        let topic = |name: &str, package: &str, kind: &str, qos: &QosProfile| {
            let parsed = Name::parse(name).map_err(|e| format!("topic name \"{name}\": {e:?}"))?;
            node.create_topic(&parsed, MessageTypeName::new(package, kind), qos)
                .map_err(|e| format!("topic {name}: {e:?}"))
        };
        let odom_topic = topic(&names.odom, "nav_msgs", "Odometry", &sensor)?;
        let scan_topic = topic(&names.scan, "sensor_msgs", "LaserScan", &sensor)?;
        let goal_topic = topic(&names.goal, "geometry_msgs", "PoseStamped", &reliable)?;
        let clock_topic = topic(&names.clock, "rosgraph_msgs", "Clock", &sensor)?;
        let empowerment_topic = topic(&names.empowerment, "cstep_msgs", "Empowerment", &reliable)?;
        let reward_topic = topic(&names.reward, "cstep_msgs", "EmpoweredReward", &reliable)?;
        let markers_topic = topic(
            &names.markers,
            "visualization_msgs",
            "MarkerArray",
            &reliable,
        )?;
        let diagnostics_topic = topic(
            &names.diagnostics,
            "diagnostic_msgs",
            "DiagnosticArray",
            &reliable,
        )?;
        let service = |name: &str, kind: &str| {
            let parsed =
                Name::parse(name).map_err(|e| format!("service name \"{name}\": {e:?}"))?;
            Ok::<_, String>((parsed, ServiceTypeName::new("cstep_msgs", kind)))
        };
        let (evaluate_name, evaluate_type) = service(&names.evaluate, "Evaluate")?;
        let (batch_name, batch_type) = service(&names.evaluate_batch, "EvaluateBatch")?;
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

/// An error mapper for creating the named entity.
pub(super) fn failed<E: std::fmt::Debug>(what: &'static str) -> impl FnOnce(E) -> String {
    move |e| format!("cannot create {what}: {e:?}")
}
