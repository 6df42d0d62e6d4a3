//! The speed limit a navigation stack obeys, from the empowerment score: the declared mapping
//! and the rate at which limits go out.
//!
//! Nav2's controller server takes a `nav2_msgs/SpeedLimit` (a percentage of each controller's
//! own maximum speed, or an absolute speed in m/s; `0.0` means "no limit") and hands it to every
//! controller plugin. The node publishes one from each score through [`SpeedLimitMapping`]:
//! full speed at and above an empowerment threshold, a floor at and below the threshold minus a
//! span, linear between — the less room the robot's dynamics leave it, the slower it may go.
//! [`RateGate`] bounds how often a limit goes out, on the scans' own stamps, so that a fast
//! LiDAR does not reconfigure the controllers at its own rate. Both are pure, so that the node
//! and its tests read the same numbers.

use std::time::Duration;

use crate::parameters::ModelKind;

/// A threshold and span where the parameters leave them unset (`.nan`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MappingDefaults {
    /// Empowerment (nats) at and above which the robot may go at full speed.
    pub full_speed_at: f64,
    /// Nats below `full_speed_at` over which the limit falls to the floor.
    pub span: f64,
}

/// The declared mapping from an empowerment score to a speed limit.
///
/// With `t = clamp((empowerment − (full_speed_at − span)) / span, 0, 1)`, the limit is
/// `floor + (100 − floor) · t` percent of full speed: 100 % at and above `full_speed_at`,
/// `floor` % at and below `full_speed_at − span`, linear between. A NaN score (none is ever
/// published, but a limit must never be NaN) reads as the floor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedLimitMapping {
    /// Empowerment (nats) at and above which the robot may go at full speed.
    pub full_speed_at: f64,
    /// Nats below `full_speed_at` over which the limit falls linearly to the floor; > 0.
    pub span: f64,
    /// The lowest limit, percent of full speed, in 1..=100. Never 0: Nav2 reads 0 as "no limit".
    pub floor: f64,
    /// `None`: limits are percentages of each controller's own maximum speed. `Some(v)`:
    /// absolute limits, the percentage of `v` m/s.
    pub max_speed: Option<f64>,
}

/// The speed-limit output as configured (`publish_speed_limit` and the `speed_limit_*`
/// parameters).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedLimitOutput {
    /// From score to limit.
    pub mapping: SpeedLimitMapping,
    /// At most this many limits per second of scan time ([`RateGate`]).
    pub rate_hz: f64,
}

/// One speed limit, as `nav2_msgs/SpeedLimit` carries it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limit {
    /// Whether `speed_limit` is a percentage (else m/s).
    pub percentage: bool,
    /// The limit: percent of full speed, or m/s. Positive, finite.
    pub speed_limit: f64,
}

impl Limit {
    /// The message that lifts any limit: Nav2 reads `speed_limit: 0.0` as "no limit".
    pub const RELEASED: Limit = Limit {
        percentage: true,
        speed_limit: 0.0,
    };
}

impl SpeedLimitMapping {
    /// The threshold and span a model's robot gets by default, from what it scores: the
    /// quadrotor's and the point mass's from the Crazyflie in the paper's arena (1.38 nats at
    /// 0.35 m from a wall, 1.86 in the open: full speed at 1.5, the floor at 0); the wheeled
    /// model's from the Husky in its hall at its top speed (`experiments/husky/
    /// speed_limit_scores.md`: 95 % of the open states score −1.04 or more, the states within
    /// 0.6 m of an obstacle −1.72 at the median: full speed at −1.05, the floor at −1.75).
    pub fn model_defaults(model: ModelKind) -> MappingDefaults {
        match model {
            ModelKind::Quadrotor | ModelKind::PointMass => MappingDefaults {
                full_speed_at: 1.5,
                span: 1.5,
            },
            ModelKind::DiffDrive => MappingDefaults {
                full_speed_at: -1.05,
                span: 0.7,
            },
        }
    }

    /// The percentage of full speed allowed at `empowerment`: in `floor..=100`, never NaN,
    /// monotone non-decreasing in the score.
    pub fn percent(&self, empowerment: f64) -> f64 {
        if empowerment.is_nan() {
            return self.floor;
        }
        let t = ((empowerment - (self.full_speed_at - self.span)) / self.span).clamp(0.0, 1.0);
        (self.floor + (100.0 - self.floor) * t).clamp(self.floor, 100.0)
    }

    /// The limit to publish at `empowerment`: [`Self::percent`], or that share of `max_speed`.
    pub fn limit(&self, empowerment: f64) -> Limit {
        let percent = self.percent(empowerment);
        match self.max_speed {
            None => Limit {
                percentage: true,
                speed_limit: percent,
            },
            Some(v) => Limit {
                percentage: false,
                speed_limit: percent / 100.0 * v,
            },
        }
    }
}

/// Lets at most one limit through per `period` of scan time (the stamps of the scans scored),
/// so the rate holds under simulated time and replays as under wall time. A stamp before the
/// last one let through means time jumped back (a simulation reset): it passes and the gate
/// starts again from it.
#[derive(Debug, Clone)]
pub struct RateGate {
    period: Duration,
    /// The stamp of the last limit let through, nanoseconds.
    last: Option<i128>,
}

impl RateGate {
    /// A gate letting through one limit per `period`.
    pub fn new(period: Duration) -> Self {
        Self { period, last: None }
    }

    /// A gate letting through at most `rate_hz` limits per second of scan time.
    pub fn per_second(rate_hz: f64) -> Self {
        Self::new(Duration::from_secs_f64(1.0 / rate_hz))
    }

    /// Whether a limit from the scan stamped `stamp_ns` (nanoseconds) goes out; if so, it is
    /// the new reference.
    pub fn admit(&mut self, stamp_ns: i128) -> bool {
        let passes = match self.last {
            Some(last) => stamp_ns < last || stamp_ns - last >= self.period.as_nanos() as i128,
            None => true,
        };
        if passes {
            self.last = Some(stamp_ns);
        }
        passes
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const MAPPING: SpeedLimitMapping = SpeedLimitMapping {
        full_speed_at: 1.5,
        span: 1.0,
        floor: 20.0,
        max_speed: None,
    };

    #[test]
    fn full_speed_above_the_threshold_floor_below_the_span_linear_between() {
        assert_eq!(MAPPING.percent(1.5), 100.0);
        assert_eq!(MAPPING.percent(7.0), 100.0);
        assert_eq!(MAPPING.percent(0.5), 20.0);
        assert_eq!(MAPPING.percent(-9.21), 20.0);
        assert_eq!(MAPPING.percent(1.0), 60.0);
        assert_eq!(MAPPING.percent(1.25), 80.0);
        assert_eq!(MAPPING.percent(f64::INFINITY), 100.0);
        assert_eq!(MAPPING.percent(f64::NEG_INFINITY), 20.0);
        assert_eq!(MAPPING.percent(f64::NAN), 20.0);
    }

    #[test]
    fn a_max_speed_makes_the_limit_absolute() {
        let absolute = SpeedLimitMapping {
            max_speed: Some(1.0),
            ..MAPPING
        };
        let limit = absolute.limit(1.0);
        assert!(!limit.percentage);
        assert_eq!(limit.speed_limit, 0.6);
        assert_eq!(
            MAPPING.limit(1.0),
            Limit {
                percentage: true,
                speed_limit: 60.0
            }
        );
    }

    #[test]
    fn the_gate_lets_one_limit_through_per_period_of_scan_time() {
        let mut gate = RateGate::per_second(10.0);
        let ms = |m: i128| m * 1_000_000;
        // Scans every 40 ms: 0, 120 and 240 ms pass (the first at least 100 ms after the last).
        let passed: Vec<i128> = (0..8)
            .map(|k| ms(40 * k))
            .filter(|&t| gate.admit(t))
            .collect();
        assert_eq!(passed, vec![ms(0), ms(120), ms(240)]);
        // Exactly one period later passes: 10 Hz scans all go out at 10 Hz.
        assert!(gate.admit(ms(340)));
        // Time jumped back: passes, and the gate starts again from there.
        assert!(gate.admit(ms(5)));
        assert!(!gate.admit(ms(50)));
        assert!(gate.admit(ms(105)));
    }

    proptest! {
        #[test]
        fn the_limit_is_monotone_bounded_and_never_nan(
            full_speed_at in -10.0..10.0f64,
            span in 1e-3..20.0f64,
            floor in 1.0..=100.0f64,
            a in prop_oneof![-1e6..1e6f64, Just(f64::NAN), Just(f64::INFINITY),
                Just(f64::NEG_INFINITY)],
            b in -1e6..1e6f64,
        ) {
            let mapping = SpeedLimitMapping { full_speed_at, span, floor, max_speed: None };
            for e in [a, b] {
                let p = mapping.percent(e);
                prop_assert!(!p.is_nan());
                prop_assert!((floor..=100.0).contains(&p), "{p} outside [{floor}, 100]");
                let limit = mapping.limit(e);
                prop_assert!(limit.percentage && limit.speed_limit == p);
            }
            if !a.is_nan() {
                let (low, high) = if a <= b { (a, b) } else { (b, a) };
                prop_assert!(mapping.percent(low) <= mapping.percent(high));
            }
        }
    }
}
