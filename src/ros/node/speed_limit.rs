//! The optional `nav2_msgs/SpeedLimit` output (`publish_speed_limit`): a limit from each score
//! through the declared mapping ([`crate::speed_limit`]), at most `speed_limit_rate` per second
//! of scan time, stamped with the scan; released (`speed_limit: 0.0`, Nav2's "no limit") when no
//! score has come for `input_timeout` and when the node stops cleanly, so that a robot is never
//! held slow by a node that no longer watches it.

use std::sync::Mutex;
use std::time::{Duration, Instant};

use ros2_client::{Node, Publisher};
use tracing::info;

use crate::ros::messages::{Header, SpeedLimit, Time};
use crate::speed_limit::{Limit, RateGate, SpeedLimitOutput};

/// How long the release at a clean stop waits for subscribers to acknowledge it.
const RELEASE_ACK_WAIT: Duration = Duration::from_secs(1);

/// The speed-limit publisher and what decides when it publishes.
pub(super) struct SpeedLimiter {
    output: SpeedLimitOutput,
    publisher: Publisher<SpeedLimit>,
    state: Mutex<State>,
}

/// What the scoring thread and the staleness watch share. Held while publishing, so that a
/// release and a limit never overtake each other.
struct State {
    gate: RateGate,
    /// Whether a limit is in force: the last message published was a limit, not a release.
    holding: bool,
    /// When the newest score came, whether or not the gate let its limit out.
    last_score: Option<Instant>,
    /// The frame of the newest limit, for its release.
    frame_id: String,
}

impl SpeedLimiter {
    /// A limiter publishing on `publisher` as `output` says.
    pub(super) fn new(output: SpeedLimitOutput, publisher: Publisher<SpeedLimit>) -> Self {
        Self {
            output,
            publisher,
            state: Mutex::new(State {
                gate: RateGate::per_second(output.rate_hz),
                holding: false,
                last_score: None,
                frame_id: String::new(),
            }),
        }
    }

    fn state(&self) -> std::sync::MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Whether a subscriber (Nav2's controller server) is matched: its scans are then scored.
    pub(super) fn wanted(&self, node: &Node) -> bool {
        self.publisher.get_subscription_count(node) > 0
    }

    /// Takes the score `empowerment` of the scan `header` names (its stamp, the odometry
    /// frame): publishes its limit unless one went out less than a period of scan time before.
    /// An error when publishing failed.
    pub(super) fn scored(&self, header: &Header, empowerment: f64) -> Result<(), String> {
        let mut state = self.state();
        state.last_score = Some(Instant::now());
        let stamp = header.stamp;
        let nanos = i128::from(stamp.sec) * 1_000_000_000 + i128::from(stamp.nanosec);
        if !state.gate.admit(nanos) {
            return Ok(());
        }
        let limit = self.output.mapping.limit(empowerment);
        state.frame_id.clone_from(&header.frame_id);
        self.publish(&mut state, header.clone(), limit)
    }

    /// Releases the limit in force, stamped `now()`, if no score has come for `timeout`.
    pub(super) fn release_if_stale(
        &self,
        timeout: Duration,
        now: impl FnOnce() -> Time,
    ) -> Result<(), String> {
        let mut state = self.state();
        let stale = state.last_score.is_none_or(|t| t.elapsed() > timeout);
        if !(state.holding && stale) {
            return Ok(());
        }
        info!(
            "speed limit released: no score for {:.2} s (input_timeout)",
            timeout.as_secs_f64()
        );
        self.release(&mut state, now())
    }

    /// At a clean stop: releases the limit in force, stamped `now`, and waits (a little) for
    /// the subscribers to acknowledge it, since the node leaves the domain next.
    pub(super) fn release_at_stop(&self, now: Time) -> Result<(), String> {
        let mut state = self.state();
        if !state.holding {
            return Ok(());
        }
        self.release(&mut state, now)?;
        match self.publisher.wait_for_acknowledgments(RELEASE_ACK_WAIT) {
            Ok(true) => {
                info!("speed limit released: the node stops");
                Ok(())
            }
            Ok(false) => Err(format!(
                "speed limit release at stop not acknowledged within {} s",
                RELEASE_ACK_WAIT.as_secs_f64()
            )),
            Err(e) => Err(format!("speed limit release at stop: {e}")),
        }
    }

    /// Publishes `speed_limit: 0.0` stamped `stamp`.
    fn release(&self, state: &mut State, stamp: Time) -> Result<(), String> {
        let header = Header {
            stamp,
            frame_id: state.frame_id.clone(),
        };
        // The first limit after a release goes out at once, whatever its stamp.
        state.gate = RateGate::per_second(self.output.rate_hz);
        self.publish(state, header, Limit::RELEASED)
    }

    fn publish(&self, state: &mut State, header: Header, limit: Limit) -> Result<(), String> {
        let message = SpeedLimit {
            header,
            percentage: limit.percentage,
            speed_limit: limit.speed_limit,
        };
        self.publisher
            .publish(message)
            .map_err(|e| format!("publishing a speed limit failed: {e}"))?;
        state.holding = limit != Limit::RELEASED;
        Ok(())
    }
}
