//! `cstep node` over real DDS (localhost, a private domain): an `/cstep/evaluate_batch` reply
//! too large for one datagram goes as DATA_FRAGs and reaches a ros2-client (RustDDS) client
//! whole, twice in a row. Every fragment of a service reply carries the request's identity as
//! inline QoS; until vendor/rustdds wrote it where the RTPS spec puts it
//! (`vendor/rustdds/CSTEP_PATCH.md`, section 3) no reader, RustDDS or Fast DDS, could parse such
//! a fragment and the reply never arrived. To a RustDDS peer that advertises loopback only the
//! node's datagram budget is the loopback MTU (~64 kB), not the 1452 bytes an rclpy client
//! gets, hence 512 states (a 74 kB reply, and a 770 kB request the client fragments too).
//! `tests/python/test_bridge.py` checks a 16-state reply (2.5 kB) with an rclpy client.

#[path = "common/live.rs"]
mod live;

use std::time::Duration;

use cstep::ros::messages::{
    EvaluateBatch, EvaluateBatchRequest, EvaluateBatchResponse, Odometry, RosService,
};
use live::{peer, reliable_qos, start_node, walls_scan, PATIENCE};
use ros2_client::{Name, ServiceMapping};

/// States in the large batch: a reply over the ~64 kB loopback budget.
const BIG: usize = 512;

/// How long a reply may take once the service answers.
const REPLY_TIMEOUT: Duration = Duration::from_secs(10);

/// How long to wait for the reply to a probe before sending another.
const PROBE_TIMEOUT: Duration = Duration::from_secs(1);

/// `k` copies of one valid state: the robot at the origin, walls 2 m away all round.
fn batch(k: usize) -> EvaluateBatchRequest {
    let scan = walls_scan();
    EvaluateBatchRequest {
        odom: vec![Odometry::default(); k],
        scan: vec![scan; k],
        ..Default::default()
    }
}

#[test]
fn a_batch_reply_sent_as_fragments_arrives_whole() {
    let _node = start_node();
    let mut peer = peer("fragmented_reply_peer");
    let qos = reliable_qos();
    let client = peer
        .create_client::<EvaluateBatchRequest, EvaluateBatchResponse>(
            ServiceMapping::Enhanced,
            &Name::parse("/cstep/evaluate_batch").unwrap(),
            &EvaluateBatch::type_name(),
            qos.clone(),
            qos,
        )
        .unwrap();
    let executor = smol::LocalExecutor::new();
    executor.spawn(peer.spinner().unwrap().spin()).detach();

    let call = |k: usize, patience: Duration| {
        let client = &client;
        async move {
            let reply = client.async_call_service(batch(k));
            let timeout = async {
                smol::Timer::after(patience).await;
                None
            };
            smol::future::or(async { reply.await.ok() }, timeout).await
        }
    };
    let exchange = async {
        client.wait_for_service(&peer).await;
        // Discovered is not yet matched both ways: probe with one state until a reply comes.
        while call(1, PROBE_TIMEOUT).await.is_none() {}
        let first = call(BIG, REPLY_TIMEOUT).await.expect("the big reply");
        let second = call(BIG, REPLY_TIMEOUT).await.expect("a second big reply");
        let after = call(1, REPLY_TIMEOUT)
            .await
            .expect("a small reply still arrives after");
        Some((first, second, after))
    };
    let give_up = async {
        smol::Timer::after(PATIENCE).await;
        None
    };
    let (first, second, after) = smol::block_on(executor.run(smol::future::or(exchange, give_up)))
        .expect("the service answers within the patience");

    for reply in [&first, &second] {
        assert_eq!((reply.empowerment.len(), reply.reward.len()), (BIG, BIG));
        assert!(reply.empowerment.iter().all(|e| e.valid), "{reply:?}");
    }
    assert_eq!(first, second, "the same request gets the same answer");
    assert_eq!(after.empowerment[0], first.empowerment[0]);
}
