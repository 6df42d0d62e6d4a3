//! A live `cstep node` over real DDS on a private localhost-only domain, and a ros2-client peer
//! of this test process to talk to it.

use std::process::{Child, Command, Stdio};
use std::time::Duration;

use cstep::ros::messages::LaserScan;
use cstep::ros::rcl::context::context_from_env;
use ros2_client::qos::{History, WhenFull};
use ros2_client::{Node, NodeName, NodeOptions, QosProfile};

/// How long discovery (and whatever the test awaits) may take before the test gives up.
pub const PATIENCE: Duration = Duration::from_secs(60);

/// A private domain for this test process: 101–220, clear of the Python tests' 1–100, offset by
/// the process id so that two runs on one machine are unlikely to share it.
fn domain() -> String {
    (101 + std::process::id() % 120).to_string()
}

/// The node under test, killed when dropped.
pub struct NodeProcess(Child);

impl Drop for NodeProcess {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Starts `cstep node` with its defaults on this process's private domain, localhost only; this
/// process joins the same domain through the same reading of the environment as the node.
pub fn start_node() -> NodeProcess {
    std::env::set_var("ROS_DOMAIN_ID", domain());
    std::env::set_var("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST");
    std::env::remove_var("ROS_LOCALHOST_ONLY");
    std::env::remove_var("ROS_STATIC_PEERS");
    NodeProcess(
        Command::new(env!("CARGO_BIN_EXE_cstep"))
            .args(["node", "--exit-with-parent"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("cstep node starts"),
    )
}

/// A ros2-client node of this process called `name`, on the domain of [`start_node`].
pub fn peer(name: &str) -> Node {
    context_from_env(true)
        .unwrap()
        .new_node(
            NodeName::new("/", name).unwrap(),
            NodeOptions::new().enable_rosout(false),
        )
        .unwrap()
}

/// Reliable, keep-last-10 QoS: what the node's services and diagnostics use.
pub fn reliable_qos() -> QosProfile {
    QosProfile::default()
        .reliability_reliable(WhenFull::Wait(Duration::from_millis(100)))
        .history(History::KeepLast { depth: 10 })
}

/// The paper's LiDAR (180 beams over 360°, 3 m) seeing walls 2 m away all round.
pub fn walls_scan() -> LaserScan {
    let increment = std::f32::consts::TAU / 180.0;
    LaserScan {
        angle_min: -std::f32::consts::PI,
        angle_max: -std::f32::consts::PI + increment * 179.0,
        angle_increment: increment,
        range_min: 0.1,
        range_max: 3.0,
        ranges: vec![2.0; 180],
        ..Default::default()
    }
}
