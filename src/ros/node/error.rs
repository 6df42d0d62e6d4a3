//! Why the node could not start, or stopped: one variant per failure, each printed exactly as
//! the user has always read it.

use crate::excerpt::excerpt;
use crate::model::urdf::UrdfError;
use crate::parameters::overrides::OverridesError;
use crate::parameters::ConfigError;
use crate::ros::rcl::args::NameError;
use crate::ros::rcl::context::ContextError;
use crate::ros::rcl::logging::LoggingError;

/// Why [`super::run`] failed.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    /// Logging could not be set up (a log already started in this process).
    #[error(transparent)]
    Logging(#[from] LoggingError),
    /// `ROS_SECURITY_ENABLE=true`, which this build cannot honour.
    #[error(
        "ROS_SECURITY_ENABLE=true, but cstep cannot run secured (its DDS, RustDDS, \
         is built without DDS Security); refusing to run unsecured"
    )]
    SecurityRequested,
    /// A parameters file or `-p` override could not be read.
    #[error(transparent)]
    ParameterOverrides(#[from] OverridesError),
    /// The parameters do not validate.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The robot description cannot be loaded.
    #[error(transparent)]
    Robot(#[from] UrdfError),
    /// The DDS context could not be set up from the environment.
    #[error(transparent)]
    Context(#[from] ContextError),
    /// The node's name or namespace is not a valid ROS name.
    #[error("node name: {0}")]
    NodeName(#[source] ros2_client::names::NameError),
    /// ros2-client could not create the node.
    #[error("cannot create the node: {0}")]
    CreateNode(#[source] ros2_client::NodeCreateError),
    /// A topic or service name does not resolve (`--ros-args` remapping, namespace).
    #[error(transparent)]
    ResolveName(#[from] NameError),
    /// Two of the node's topics, or its two services, resolve to one name.
    #[error(
        "{kind} {}: {first} and {second} both resolve to it ({why}); give each its own name \
         (--ros-args -r, or the *_topic and *_service parameters)",
        excerpt(name)
    )]
    SharedName {
        /// "topic" or "service".
        kind: &'static str,
        /// The name they share.
        name: String,
        /// One of them, with its type ("the scan subscription (sensor_msgs/msg/LaserScan)").
        first: String,
        /// The other.
        second: String,
        /// Why that cannot work.
        why: &'static str,
    },
    /// A resolved topic name ros2-client does not accept.
    #[error("topic name \"{}\": {reason}", excerpt(name))]
    TopicName {
        /// The topic name.
        name: String,
        /// ros2-client's reason.
        #[source]
        reason: ros2_client::names::NameError,
    },
    /// A resolved service name ros2-client does not accept.
    #[error("service name \"{}\": {reason}", excerpt(name))]
    ServiceName {
        /// The service name.
        name: String,
        /// ros2-client's reason.
        #[source]
        reason: ros2_client::names::NameError,
    },
    /// The DDS topic could not be created.
    #[error("topic {name}: {reason}")]
    Topic {
        /// The topic name.
        name: String,
        /// ros2-client's reason.
        #[source]
        reason: ros2_client::CreateError,
    },
    /// A subscription, publisher or server could not be created.
    #[error("cannot create {what}: {reason}")]
    Create {
        /// What, e.g. "the odometry subscription".
        what: &'static str,
        /// ros2-client's reason.
        #[source]
        reason: ros2_client::CreateError,
    },
    /// The DDS spinner could not be started.
    #[error("cannot start the node's DDS event loop: {0}")]
    Spinner(#[source] ros2_client::CreateError),
    /// The scoring thread panicked.
    #[error("the scoring thread failed")]
    ScoringThread,
    /// Another node answers under this node's names (found by the node's watch for rivals).
    #[error("{0}")]
    Rival(String),
}
