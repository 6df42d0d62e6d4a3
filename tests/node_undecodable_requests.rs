//! `cstep node` over real DDS (localhost, a private domain): a service request that is not
//! decodable CDR is dropped, counted in the diagnostics' `inputs_rejected` and named there, as
//! an undecodable topic message is (the servers once dropped it uncounted).

#[path = "common/live.rs"]
mod live;

use std::time::Duration;

use cstep::ros::messages::{
    DiagnosticArray, Evaluate, LaserScan, Odometry, RosMessage, RosService,
};
use futures::StreamExt;
use live::{peer, reliable_qos, start_node, walls_scan, PATIENCE};
use ros2_client::{Message, MessageTypeName, Name, ServiceMapping};
use serde::{Deserialize, Serialize};

/// What the test sends as a `cstep_msgs/Evaluate` request: one byte, where the odometry's
/// header should begin.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct OneByte(u8);

impl Message for OneByte {}

#[test]
fn an_undecodable_evaluate_request_is_counted_and_named_in_diagnostics() {
    let _node = start_node();
    let mut peer = peer("undecodable_peer");
    let qos = reliable_qos();
    let client = peer
        .create_client::<OneByte, OneByte>(
            ServiceMapping::Enhanced,
            &Name::parse("/cstep/evaluate").unwrap(),
            &Evaluate::type_name(),
            qos.clone(),
            qos.clone(),
        )
        .unwrap();
    let topic = peer
        .create_topic(
            &Name::parse("/diagnostics").unwrap(),
            DiagnosticArray::type_name(),
            &qos,
        )
        .unwrap();
    let diagnostics = peer
        .create_subscription::<DiagnosticArray>(&topic, None)
        .unwrap();
    // Diagnostics name the last problem only while the inputs are fresh: feed valid ones.
    let publisher = |name: &str, type_name: MessageTypeName| {
        let topic = Name::parse(name).unwrap();
        peer.create_topic(&topic, type_name, &qos).unwrap()
    };
    let odom_topic = publisher("/odom", Odometry::type_name());
    let scan_topic = publisher("/scan", LaserScan::type_name());
    let odom = peer
        .create_publisher::<Odometry>(&odom_topic, None)
        .unwrap();
    let scan = peer
        .create_publisher::<LaserScan>(&scan_topic, None)
        .unwrap();
    let beams = walls_scan();
    let executor = smol::LocalExecutor::new();
    executor.spawn(peer.spinner().unwrap().spin()).detach();
    executor
        .spawn(async {
            loop {
                // A lost sample is made up for by the next.
                let _ = odom.publish(Odometry::default());
                let _ = scan.publish(beams.clone());
                smol::Timer::after(Duration::from_millis(100)).await;
            }
        })
        .detach();

    let sent = 3;
    let exchange = async {
        client.wait_for_service(&peer).await;
        for _ in 0..sent {
            client.async_send_request(OneByte(7)).await.unwrap();
        }
        let mut stream = std::pin::pin!(diagnostics.async_stream());
        while let Some(received) = stream.next().await {
            let Ok((array, _)) = received else { continue };
            let Some(status) = array.status.first() else {
                continue;
            };
            let rejected = status.values.iter().find(|kv| kv.key == "inputs_rejected");
            if rejected.is_some_and(|kv| kv.value == sent.to_string()) && status.level == 1 {
                return Some(status.message.clone());
            }
        }
        None
    };
    let give_up = async {
        smol::Timer::after(PATIENCE).await;
        None
    };
    let said = smol::block_on(executor.run(smol::future::or(exchange, give_up)));
    let message = said.expect("diagnostics count the undecodable requests");
    assert!(
        message.starts_with("evaluate: undecodable request dropped: "),
        "{message}"
    );
}
