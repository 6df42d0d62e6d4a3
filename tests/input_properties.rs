//! Property tests over the shared input validation (`cstep::ros::convert`) and the estimator:
//! arbitrary odometry, scans and goals — NaN, ±inf, subnormals, huge and tiny magnitudes, any
//! length up to past the beam limit — never panic and never publish a non-finite number. Each
//! input is either rejected with a short one-line error naming a field, or scored with finite
//! outputs, exactly as the node, the services and `cstep eval` do.
//!
//! `cargo test` runs proptest's default 256 cases per property (`PROPTEST_CASES` overrides it);
//! the long run is documented in `experiments/protocol.md` ("The long property-test run"):
//! `PROPTEST_CASES=10000000 cargo test --release --test input_properties`.

use std::f64::consts::{PI, TAU};
use std::sync::OnceLock;

use cstep::estimator::Estimator;
use cstep::input::{InputError, MAX_ANGULAR_RATE, MAX_BEAMS, MAX_COORDINATE, MAX_SPEED};
use cstep::occupancy::ScanFrame;
use cstep::parameters::{Settings, DEFAULT_NODE_NAME};
use cstep::ros::convert::{
    empowerment_message, goal_position, laser_scan_to_scan, odometry_to_state, reward_message,
};
use cstep::ros::messages::{Header, LaserScan, Odometry, Point, Quaternion, Vector3};
use cstep::scoring::{score, unscorable, Score};
use proptest::prelude::*;

/// Longest error message accepted.
const MAX_ERROR_CHARS: usize = 320;

/// Longest number in an error message: an `f64` printed shortest-roundtrip takes at most 24
/// characters (`-2.2250738585072014e-308`); a 1e-160 component printed
/// 160 digits.
const MAX_NUMBER_CHARS: usize = 24;

/// Numbers from every class an `f64` has, weighted towards the edges: proptest's full range
/// (NaN, ±inf, subnormals, zeros, normals), extreme magnitudes, and everyday values.
fn wild_f64() -> impl Strategy<Value = f64> + Clone {
    prop_oneof![
        3 => proptest::num::f64::ANY,
        2 => prop::sample::select(vec![
            0.0,
            -0.0,
            1e-160,
            -1e-300,
            f64::MIN_POSITIVE,
            5e-324,
            1e155,
            1e300,
            f64::MAX,
            f64::MIN,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            MAX_COORDINATE,
            MAX_SPEED,
            1e39,
        ]),
        3 => -10.0..10.0,
    ]
}

/// The same for the `float32` fields of a scan.
fn wild_f32() -> impl Strategy<Value = f32> + Clone {
    prop_oneof![
        3 => proptest::num::f32::ANY,
        2 => prop::sample::select(vec![
            0.0,
            -0.0,
            1e-40,
            f32::MIN_POSITIVE,
            f32::MAX,
            f32::MIN,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            1e30,
            std::f32::consts::TAU,
            std::f32::consts::TAU.next_up(),
        ]),
        3 => -10.0f32..10.0,
    ]
}

/// Ranges of any length up to past [`MAX_BEAMS`], with any values (REP 117 gives each a
/// meaning); the longest are uniform, to keep a case cheap.
fn ranges() -> impl Strategy<Value = Vec<f32>> {
    prop_oneof![
        8 => prop::collection::vec(wild_f32(), 0..400),
        1 => (MAX_BEAMS - 1..=MAX_BEAMS + 1, wild_f32()).prop_map(|(n, r)| vec![r; n]),
    ]
}

fn point(c: impl Strategy<Value = f64> + Clone) -> impl Strategy<Value = Point> {
    (c.clone(), c.clone(), c).prop_map(|(x, y, z)| Point { x, y, z })
}

fn vector(c: impl Strategy<Value = f64> + Clone) -> impl Strategy<Value = Vector3> {
    (c.clone(), c.clone(), c).prop_map(|(x, y, z)| Vector3 { x, y, z })
}

/// Odometry with these pose and twist parts (the rest default).
fn odometry(
    (position, orientation, linear, angular): (Point, Quaternion, Vector3, Vector3),
) -> Odometry {
    let mut odom = Odometry::default();
    odom.pose.pose.position = position;
    odom.pose.pose.orientation = orientation;
    odom.twist.twist.linear = linear;
    odom.twist.twist.angular = angular;
    odom
}

/// Odometry with every field the validation reads drawn from [`wild_f64`].
fn wild_odometry() -> impl Strategy<Value = Odometry> {
    let quaternion = (wild_f64(), wild_f64(), wild_f64(), wild_f64())
        .prop_map(|(x, y, z, w)| Quaternion { x, y, z, w });
    (
        point(wild_f64()),
        quaternion,
        vector(wild_f64()),
        vector(wild_f64()),
    )
        .prop_map(odometry)
}

/// A scan with every field the validation reads drawn independently.
fn wild_scan() -> impl Strategy<Value = LaserScan> {
    (
        (wild_f32(), wild_f32(), wild_f32()),
        (wild_f32(), wild_f32()),
        ranges(),
        any::<u32>(),
    )
        .prop_map(
            |((angle_min, angle_max, angle_increment), (range_min, range_max), ranges, ns)| {
                let mut scan = LaserScan {
                    angle_min,
                    angle_max,
                    angle_increment,
                    range_min,
                    range_max,
                    ranges,
                    ..Default::default()
                };
                scan.header.stamp.nanosec = ns;
                scan
            },
        )
}

/// Coordinates a valid position may have: anywhere within ±[`MAX_COORDINATE`], tiny and
/// subnormal ones included.
fn coordinate() -> impl Strategy<Value = f64> + Clone {
    prop_oneof![
        -MAX_COORDINATE..=MAX_COORDINATE,
        -10.0..10.0,
        prop::sample::select(vec![0.0, -0.0, 5e-324, -1e-300, MAX_COORDINATE]),
    ]
}

/// Odometry the validation must accept: a position within bounds, a rotation, a speed up to
/// [`MAX_SPEED`] and a rate up to [`MAX_ANGULAR_RATE`] (just inside, for rounding).
fn valid_odometry() -> impl Strategy<Value = Odometry> {
    let unit = (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64);
    let direction = unit.prop_filter_map("a direction", |(x, y, z)| {
        let n = (x * x + y * y + z * z).sqrt();
        (n > 1e-3).then(|| [x / n, y / n, z / n])
    });
    let rate = |limit: f64| {
        (
            direction.clone(),
            prop_oneof![Just(0.0), 0.0..=limit * 0.999],
        )
            .prop_map(|(d, s)| Vector3 {
                x: d[0] * s,
                y: d[1] * s,
                z: d[2] * s,
            })
    };
    let rotation = (direction.clone(), -PI..PI).prop_map(|(axis, angle)| {
        let (s, c) = (angle / 2.0).sin_cos();
        Quaternion {
            x: axis[0] * s,
            y: axis[1] * s,
            z: axis[2] * s,
            w: c,
        }
    });
    (
        point(coordinate()),
        rotation,
        rate(MAX_SPEED),
        rate(MAX_ANGULAR_RATE),
    )
        .prop_map(odometry)
}

/// A scan the validation must accept: its beams spanning up to one turn either way round,
/// bearings within ±π, limits as a LiDAR reports them, and any range values.
fn valid_scan() -> impl Strategy<Value = LaserScan> {
    // Ranges clear of the robot too, so that most cases roll out rather than stop at a robot
    // already in collision.
    let ranges = prop_oneof![
        prop::collection::vec(wild_f32(), 0..400),
        prop::collection::vec(0.5f32..20.0, 0..400),
        prop::collection::vec(Just(f32::INFINITY), 0..400),
    ];
    (
        ranges,
        -PI..PI,
        prop_oneof![0.01..TAU, Just(TAU * 359.0 / 360.0)],
        any::<bool>(),
        (0.0f32..1.0, 1.0f32..1e4),
    )
        .prop_map(|(ranges, start, span, clockwise, (range_min, range_max))| {
            let steps = ranges.len().saturating_sub(1).max(1) as f64;
            // Starting on the side it turns away from, it ends within ±π too.
            let (start, span) = if clockwise {
                (start.abs(), -span)
            } else {
                (-start.abs(), span)
            };
            let increment = span / steps;
            let end = start + increment * ranges.len().saturating_sub(1) as f64;
            LaserScan {
                angle_min: start as f32,
                angle_max: end as f32,
                angle_increment: increment as f32,
                range_min,
                range_max,
                ranges,
                ..Default::default()
            }
        })
}

/// The estimators the outputs are checked with: the built-in quadrotor (2D areas, unknown space
/// occupied) and a point mass measuring 3D volumes with unknown space free.
fn estimators() -> &'static [(Estimator, f64)] {
    static ESTIMATORS: OnceLock<Vec<(Estimator, f64)>> = OnceLock::new();
    ESTIMATORS.get_or_init(|| {
        let point_mass: Vec<String> =
            ["model:=point_mass", "volume_dims:=3", "unknown_space:=free"]
                .map(String::from)
                .to_vec();
        [
            Settings::builtin(),
            Settings::load(None, DEFAULT_NODE_NAME, &point_mass).unwrap(),
        ]
        .iter()
        .map(|s| (Estimator::from_settings(s).unwrap(), s.safety_coefficient))
        .collect()
    })
}

/// Asserts an error is what the contract promises: a field, and one short line with every
/// number in it printed compactly.
fn check_error(error: &InputError) -> Result<(), TestCaseError> {
    let text = error.to_string();
    prop_assert!(!error.field.is_empty(), "{text}");
    prop_assert!(!text.contains('\n'), "one line: {text}");
    prop_assert!(
        text.chars().count() <= MAX_ERROR_CHARS,
        "{} chars: {text}",
        text.len()
    );
    let longest_number = text
        .split(|c: char| !(c.is_ascii_digit() || ".eE+-".contains(c)))
        .map(str::len)
        .max();
    prop_assert!(
        longest_number <= Some(MAX_NUMBER_CHARS),
        "a long number: {text}"
    );
    Ok(())
}

/// Scores a validated input as the node publishes it, and asserts every published number is
/// finite.
fn check_scored(
    which: usize,
    odom: &Odometry,
    scan: &LaserScan,
    goal: Option<&Point>,
) -> Result<(), TestCaseError> {
    let state = odometry_to_state(odom).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let parsed = laser_scan_to_scan(scan).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let goal = match goal.map(goal_position).transpose() {
        Ok(goal) => goal,
        Err(e) => return check_error(&e),
    };
    let (estimator, c) = &estimators()[which];
    let seen = (&parsed, ScanFrame::Body);
    let Score { estimate, reward } = score(estimator, &state, seen, goal.as_ref(), *c, false);
    let e = empowerment_message(Header::default(), &estimate, *c);
    let r = reward_message(Header::default(), &reward, *c, estimate.valid());
    for (name, v) in [
        ("empowerment", e.empowerment),
        ("reachable_volume", e.reachable_volume),
        ("terminal_volume", e.terminal_volume),
        ("free_volume", e.free_volume),
        ("horizon", e.horizon),
        ("reward", r.reward),
        ("task_reward", r.task_reward),
        ("empowerment_term", r.empowerment_term),
    ] {
        prop_assert!(v.is_finite(), "{name} = {v}: {e:?} {r:?}");
    }
    prop_assert!((0.0..=1.0).contains(&r.task_reward), "{r:?}");
    // No score is below the one a rejected input gets.
    prop_assert!(r.reward >= unscorable(estimator, *c).reward.reward, "{r:?}");
    Ok(())
}

proptest! {
    /// Any odometry is a state with finite, bounded parts, or an error naming a field.
    #[test]
    fn any_odometry_is_a_bounded_state_or_a_short_error(odom in wild_odometry()) {
        match odometry_to_state(&odom) {
            Ok(state) => {
                prop_assert!(state.position.amax() <= MAX_COORDINATE);
                prop_assert!(state.velocity.norm() <= MAX_SPEED * (1.0 + 1e-9));
                prop_assert!(state.body_rates.norm() <= MAX_ANGULAR_RATE);
                prop_assert!((state.attitude.norm() - 1.0).abs() < 1e-9);
            }
            Err(e) => check_error(&e)?,
        }
    }

    /// Any scan is one whose beams span at most one turn plus two increments and agree with
    /// `angle_max` within an increment (once, 1e30 rad between two beams), or an
    /// error naming a field.
    #[test]
    fn any_scan_is_a_meaningful_one_or_a_short_error(msg in wild_scan()) {
        match laser_scan_to_scan(&msg) {
            Ok(scan) => {
                let n = scan.ranges.len();
                prop_assert!(n <= MAX_BEAMS);
                for v in [scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max] {
                    prop_assert!(v.is_finite());
                }
                prop_assert!(0.0 <= scan.range_min && scan.range_min < scan.range_max);
                let increment = scan.angle_increment.abs();
                prop_assert!(increment > 0.0 && increment <= TAU as f32 as f64);
                if n > 0 {
                    let last = scan.angle_min + scan.angle_increment * (n - 1) as f64;
                    prop_assert!((last - scan.angle_min).abs() <= TAU + 2.0 * increment + 1e-6);
                    prop_assert!(
                        (last - msg.angle_max as f64).abs() <= increment * (1.0 + 1e-6) + 1e-6,
                        "last beam at {last}, angle_max {}", msg.angle_max
                    );
                }
            }
            Err(e) => check_error(&e)?,
        }
    }

    /// Any goal is a position within bounds or an error naming it.
    #[test]
    fn any_goal_is_bounded_or_a_short_error(goal in point(wild_f64())) {
        match goal_position(&goal) {
            Ok(g) => prop_assert!(g.amax() <= MAX_COORDINATE),
            Err(e) => check_error(&e)?,
        }
    }

    /// Arbitrary inputs, scored as the node scores them: rejected, or every published number
    /// finite.
    #[test]
    fn any_input_is_rejected_or_scored_finite(
        odom in prop_oneof![wild_odometry(), valid_odometry()],
        scan in prop_oneof![wild_scan(), valid_scan()],
        goal in prop::option::of(point(wild_f64())),
        which in 0..2usize,
    ) {
        match (odometry_to_state(&odom), laser_scan_to_scan(&scan)) {
            (Ok(_), Ok(_)) => check_scored(which, &odom, &scan, goal.as_ref())?,
            (Err(e), _) | (_, Err(e)) => check_error(&e)?,
        }
    }

    /// Inputs within every bound are accepted, whatever their ranges hold, and score finite.
    #[test]
    fn valid_inputs_are_accepted_and_score_finite(
        odom in valid_odometry(),
        scan in valid_scan(),
        goal in prop::option::of(point(coordinate())),
        which in 0..2usize,
    ) {
        if let Err(e) = odometry_to_state(&odom) {
            return Err(TestCaseError::fail(format!("rejected {odom:?}: {e}")));
        }
        if let Err(e) = laser_scan_to_scan(&scan) {
            return Err(TestCaseError::fail(format!("rejected {scan:?}: {e}")));
        }
        check_scored(which, &odom, &scan, goal.as_ref())?;
    }
}
