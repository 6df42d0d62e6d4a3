//! A fuzz loop over the CDR decoding of everything `cstep node` reads from DDS:
//! random and mutated bytes go through the decode path the node's DDS readers use, and whatever
//! decodes goes on through the node's input checks (`src/ros/convert.rs`). Nothing may panic.
//!
//! The node never decodes CDR itself: ros2-client's readers do, through RustDDS. A DATA
//! payload is split by `SerializedPayload::from_bytes` into its encapsulation header and body;
//! a topic's `SimpleDataReaderCdr` accepts the representations `CDRDeserializerAdapter` lists and
//! decodes the body with it (`vendor/rustdds/src/dds/with_key/simpledatareader.rs`), and a
//! service's reader (ros2-client `service/wrappers.rs`, `ServiceMapping::Enhanced`, the one the
//! node serves) accepts CDR_LE and CDR_BE and decodes the body with
//! `deserialize_from_cdr_with_rep_id`. These are those same public functions, called in that
//! order. The RTPS layer below (submessages, fragments) is not fuzzed here.
//!
//! Seeds are the rclpy-made fixtures in `tests/data/cdr/` (`generate.py`); the types only
//! ros2-client's own spinner reads (`/clock`, parameter requests, `ros_discovery_info`) have no
//! rclpy fixture and are seeded with values encoded here. Every input is built from its own
//! random stream (the run's seed, stream = the input's index), so a failure is reproducible
//! from the seed and index alone, and its bytes are printed.
//!
//! `cargo test` runs 20 000 inputs (well under a second). The long run (`make fuzz-cdr`):
//!
//! ```sh
//! CDR_FUZZ_INPUTS=10000000 CDR_FUZZ_SEED=1 cargo test --test cdr_fuzz -- --nocapture
//! ```

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::time::Instant;

use byteorder::LittleEndian;
use cstep::cloud::{CloudInput, CloudOptions};
use cstep::ros::convert::{
    goal_position, laser_scan_to_scan, odometry_to_state, point_cloud_to_scan,
};
use cstep::ros::messages::{
    EvaluateBatchRequest, EvaluateRequest, LaserScan, Odometry, PointCloud2, PoseStamped,
};
use nalgebra::UnitQuaternion;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use ros2_client::builtin_interfaces;
use ros2_client::dds::rustdds::bytes::Bytes;
use ros2_client::dds::rustdds::no_key::DeserializerAdapter;
use ros2_client::dds::rustdds::serialization::deserialize_from_cdr_with_rep_id;
use ros2_client::dds::rustdds::{
    CDRDeserializerAdapter, RepresentationIdentifier, SerializedPayload,
};
use ros2_client::entities_info::{NodeEntitiesInfo, ParticipantEntitiesInfo};
use ros2_client::rcl_interfaces::SetParametersRequest;
use ros2_client::{Gid, NodeName, Parameter, ROSTime};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// Inputs when `CDR_FUZZ_INPUTS` is unset: enough for `cargo test` to catch a regression fast.
const DEFAULT_INPUTS: u64 = 20_000;

/// The run's seed when `CDR_FUZZ_SEED` is unset.
const DEFAULT_SEED: u64 = 12;

/// The longest random input: a large message, past every seed (the biggest is ~1.7 kB).
const LARGE: usize = 1 << 16;

/// The encapsulation headers a payload may carry: the three the readers accept
/// (CDR_LE, CDR_BE, PL_CDR_LE) and one they refuse (PL_CDR_BE).
const HEADERS: [[u8; 4]; 4] = [[0, 1, 0, 0], [0, 0, 0, 0], [0, 3, 0, 0], [0, 2, 0, 0]];

/// What one input did: decoded (and went through the checks), or was refused by the decoder.
type Run = fn(&[u8]) -> bool;

/// One message type the node reads, with how to decode and check it and its seeds.
struct Target {
    /// The topic or service and the type, as the report prints it.
    name: &'static str,
    /// Decodes an input as the node's reader does and, if it decodes, checks it as the node does.
    run: Run,
    /// Well-formed payloads (encapsulation header included) to mutate.
    seeds: Vec<Vec<u8>>,
}

/// Decodes `bytes` as a topic's DDS reader does: the payload header, a representation the CDR
/// adapter accepts, then the adapter's own decoding of the body.
fn topic<M: DeserializeOwned + 'static>(bytes: &[u8]) -> Option<M> {
    let payload = SerializedPayload::from_bytes(&Bytes::copy_from_slice(bytes)).ok()?;
    let encoding = *<CDRDeserializerAdapter<M> as DeserializerAdapter<M>>::supported_encodings()
        .iter()
        .find(|r| **r == payload.representation_identifier)?;
    CDRDeserializerAdapter::<M>::from_bytes(&payload.value, encoding).ok()
}

/// Decodes `bytes` as a service's request reader does under `ServiceMapping::Enhanced`: the
/// payload header, CDR_LE or CDR_BE (ros2-client's `ServiceDeserializerAdapter::REPR_IDS`,
/// private there), then the request from the whole body.
fn request<R: DeserializeOwned>(bytes: &[u8]) -> Option<R> {
    let payload = SerializedPayload::from_bytes(&Bytes::copy_from_slice(bytes)).ok()?;
    let encoding = payload.representation_identifier;
    if encoding != RepresentationIdentifier::CDR_LE && encoding != RepresentationIdentifier::CDR_BE
    {
        return None;
    }
    deserialize_from_cdr_with_rep_id::<R>(&payload.value, encoding)
        .ok()
        .map(|(request, _)| request)
}

/// The message types the node reads, each with its seeds.
fn targets() -> Vec<Target> {
    let fixture = |name: &str| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/data/cdr/{name}.cdr"));
        std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    };
    // `/clock` carries a `builtin_interfaces/Time`: the stamp rclpy wrote at the start of a header.
    let clock = fixture("header")[..12].to_vec();
    let node_info = NodeEntitiesInfo::new(NodeName::new("/ns", "cstep_node").unwrap());
    let participant = ParticipantEntitiesInfo::new(Gid::from([7; 16]), vec![node_info]);
    let set_parameters = SetParametersRequest {
        parameter: vec![Parameter {
            name: "safety_coefficient".into(),
            value: ros2_client::ParameterValue::Double(0.5),
        }
        .into()],
    };
    vec![
        Target {
            name: "odom nav_msgs/Odometry",
            run: |b| {
                topic::<Odometry>(b)
                    .map(|m| drop(odometry_to_state(&m)))
                    .is_some()
            },
            seeds: vec![fixture("odometry")],
        },
        Target {
            name: "scan sensor_msgs/LaserScan",
            run: |b| {
                topic::<LaserScan>(b)
                    .map(|m| drop(laser_scan_to_scan(&m)))
                    .is_some()
            },
            seeds: vec![fixture("laser_scan"), fixture("laser_scan_empty")],
        },
        Target {
            name: "cloud sensor_msgs/PointCloud2",
            // Read as the node reads a cloud (a small bound on points, so that a huge width
            // and height cost a stride, not time), tilted so the rotation is not trivial.
            run: |b| {
                topic::<PointCloud2>(b)
                    .map(|m| drop(point_cloud_to_scan(&m, &tilted(), &cloud_input())))
                    .is_some()
            },
            seeds: vec![fixture("point_cloud2"), fixture("point_cloud2_big_endian")],
        },
        Target {
            name: "goal_pose geometry_msgs/PoseStamped",
            run: |b| {
                topic::<PoseStamped>(b)
                    .map(|m| drop(goal_position(&m.pose.position)))
                    .is_some()
            },
            seeds: vec![fixture("pose_stamped")],
        },
        Target {
            name: "/cstep/evaluate request",
            // The goal too, `has_goal` or not (the node checks it with `has_goal` set).
            run: |b| {
                request::<EvaluateRequest>(b)
                    .map(|r| {
                        drop(odometry_to_state(&r.odom));
                        drop(laser_scan_to_scan(&r.scan));
                        drop(goal_position(&r.goal));
                    })
                    .is_some()
            },
            seeds: vec![fixture("evaluate_request")],
        },
        Target {
            name: "/cstep/evaluate_batch request",
            // Every entry, whatever the arrays' lengths (the node pairs them only when they
            // agree) and every goal, `has_goal` or not (the node checks those with it set).
            run: |b| {
                request::<EvaluateBatchRequest>(b)
                    .map(|r| {
                        r.odom.iter().for_each(|o| drop(odometry_to_state(o)));
                        r.scan.iter().for_each(|s| drop(laser_scan_to_scan(s)));
                        r.goal.iter().for_each(|g| drop(goal_position(g)));
                    })
                    .is_some()
            },
            seeds: vec![fixture("evaluate_batch_request")],
        },
        // ros2-client's spinner reads these for the node; it converts /clock to a ROSTime and
        // parameters to `Parameter`s before the node's callback sees them.
        Target {
            name: "/clock builtin_interfaces/Time",
            run: |b| {
                topic::<builtin_interfaces::Time>(b)
                    .map(|t| ROSTime::from(t).to_nanos())
                    .is_some()
            },
            seeds: vec![clock],
        },
        Target {
            name: "set_parameters request",
            run: |b| {
                request::<SetParametersRequest>(b)
                    .map(|r| {
                        r.parameter
                            .into_iter()
                            .for_each(|p| drop(Parameter::from(p)))
                    })
                    .is_some()
            },
            seeds: vec![encoded(&set_parameters)],
        },
        Target {
            name: "ros_discovery_info ParticipantEntitiesInfo",
            run: |b| topic::<ParticipantEntitiesInfo>(b).is_some(),
            seeds: vec![encoded(&participant)],
        },
    ]
}

/// A robot rolled and pitched by 0.2 rad and turned by 1 rad.
fn tilted() -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(0.2, -0.2, 1.0)
}

/// The node's cloud reading with its default band and ranges and at most 4096 points.
fn cloud_input() -> CloudInput {
    CloudInput {
        options: CloudOptions {
            band: (-0.2, 0.2),
            range_min: 0.1,
            range_max: 10.0,
            field_of_view: 3.0,
        },
        max_points: 4096,
    }
}

/// `value` as a CDR_LE payload, for the types with no rclpy fixture.
fn encoded<T: Serialize>(value: &T) -> Vec<u8> {
    let mut bytes = HEADERS[0].to_vec();
    bytes.extend(cdr_encoding::to_vec::<T, LittleEndian>(value).unwrap());
    bytes
}

/// Input `index` of a run for `target`, from its own random stream.
fn input(base: &ChaCha8Rng, index: u64, target: &Target, all_seeds: &[&[u8]]) -> Vec<u8> {
    let mut rng = base.clone();
    rng.set_stream(index);
    let seed = &target.seeds[rng.random_range(0..target.seeds.len())];
    match rng.random_range(0..10) {
        // Random bytes of a random length, mostly up to twice the seed's, some large; half
        // behind a header the reader accepts, so the body reaches the decoder.
        0..=2 => {
            let len = if rng.random_bool(0.05) {
                rng.random_range(0..LARGE)
            } else {
                rng.random_range(0..2 * seed.len())
            };
            let mut bytes = vec![0; len];
            rng.fill(&mut bytes[..]);
            if len >= 4 && rng.random_bool(0.5) {
                bytes[..4].copy_from_slice(&HEADERS[rng.random_range(0..3)]);
            }
            bytes
        }
        // A seed with one to eight mutations.
        _ => {
            let mut bytes = seed.clone();
            for _ in 0..rng.random_range(1..=8) {
                mutate(&mut rng, &mut bytes, all_seeds);
            }
            bytes
        }
    }
}

/// Applies one random mutation to `bytes`.
fn mutate(rng: &mut ChaCha8Rng, bytes: &mut Vec<u8>, all_seeds: &[&[u8]]) {
    let len = bytes.len();
    // An offset in the CDR body, aligned to `align` relative to it (as CDR aligns), or None
    // when the body holds no such field.
    let aligned = |rng: &mut ChaCha8Rng, align: usize| {
        (len >= 4 + align).then(|| 4 + rng.random_range(0..=(len - 4 - align) / align) * align)
    };
    match rng.random_range(0..9) {
        0 if len > 0 => {
            let i = rng.random_range(0..len);
            bytes[i] ^= 1 << rng.random_range(0..8);
        }
        1 if len > 0 => {
            let i = rng.random_range(0..len);
            bytes[i] = [0x00, 0xFF, rng.random()][rng.random_range(0..3)];
        }
        2 => bytes.truncate(rng.random_range(0..=len)),
        3 => {
            let extra = rng.random_range(1..=64);
            bytes.extend((0..extra).map(|_| rng.random::<u8>()));
        }
        // A length (or any 4-byte field) set to a huge, edge or off-by-one value.
        4 => {
            if let Some(at) = aligned(rng, 4) {
                let body = (len - 4) as u32;
                let values = [
                    u32::MAX,
                    0x8000_0000,
                    0x7FFF_FFFF,
                    0x4000_0000,
                    0x10000,
                    body,
                    body + 1,
                    0,
                ];
                let value = values[rng.random_range(0..values.len())];
                bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
            }
        }
        // A float64 field set to a value the checks must refuse.
        5 => {
            if let Some(at) = aligned(rng, 8) {
                let values = [
                    f64::NAN,
                    f64::INFINITY,
                    -f64::INFINITY,
                    f64::MAX,
                    1e39,
                    5e-324,
                    -0.0,
                ];
                let value = values[rng.random_range(0..values.len())];
                bytes[at..at + 8].copy_from_slice(&value.to_le_bytes());
            }
        }
        // A float32 field (a scan's angles, ranges) likewise.
        6 => {
            if let Some(at) = aligned(rng, 4) {
                let values = [f32::NAN, f32::INFINITY, f32::MAX, 1e-45, 0.0];
                let value = values[rng.random_range(0..values.len())];
                bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
            }
        }
        // A splice: this input's head and another seed's tail.
        7 => {
            let other = all_seeds[rng.random_range(0..all_seeds.len())];
            bytes.truncate(rng.random_range(0..=len));
            bytes.extend_from_slice(&other[rng.random_range(0..=other.len())..]);
        }
        // Another encapsulation header: big-endian reads every length byte-swapped.
        _ => {
            if len >= 4 {
                bytes[..4].copy_from_slice(&HEADERS[rng.random_range(0..HEADERS.len())]);
            }
        }
    }
}

/// A number from the environment variable `name`, or `default` when it is unset.
fn env_number(name: &str, default: u64) -> u64 {
    std::env::var(name).map_or(default, |v| {
        v.parse()
            .unwrap_or_else(|_| panic!("{name}={v:?} is not a number"))
    })
}

/// Per target: inputs, decoded, panicked.
#[derive(Default, Clone, Copy)]
struct Counts {
    inputs: u64,
    decoded: u64,
    panicked: u64,
}

#[test]
fn no_input_makes_the_decode_path_or_the_checks_panic() {
    let inputs = env_number("CDR_FUZZ_INPUTS", DEFAULT_INPUTS);
    let seed = env_number("CDR_FUZZ_SEED", DEFAULT_SEED);
    let targets = targets();
    for target in &targets {
        for (i, s) in target.seeds.iter().enumerate() {
            assert!((target.run)(s), "{}: seed {i} does not decode", target.name);
        }
    }
    let all_seeds: Vec<&[u8]> = targets
        .iter()
        .flat_map(|t| t.seeds.iter().map(Vec::as_slice))
        .collect();
    let base = ChaCha8Rng::seed_from_u64(seed);
    let mut counts = vec![Counts::default(); targets.len()];
    let started = Instant::now();
    for index in 0..inputs {
        let which = (index % targets.len() as u64) as usize;
        let target = &targets[which];
        let bytes = input(&base, index, target, &all_seeds);
        let count = &mut counts[which];
        count.inputs += 1;
        match catch_unwind(AssertUnwindSafe(|| (target.run)(&bytes))) {
            Ok(decoded) => count.decoded += u64::from(decoded),
            Err(_) => {
                count.panicked += 1;
                let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
                eprintln!(
                    "PANIC: CDR_FUZZ_SEED={seed}, input {index}, {}, {} bytes: {hex}",
                    target.name,
                    bytes.len()
                );
            }
        }
    }
    let seconds = started.elapsed().as_secs_f64();
    println!("CDR fuzz: {inputs} inputs, seed {seed}, {seconds:.1} s");
    println!(
        "{:<44} {:>10} {:>10} {:>10} {:>7}",
        "type", "inputs", "decoded", "rejected", "panics"
    );
    for (target, c) in targets.iter().zip(&counts) {
        let rejected = c.inputs - c.decoded - c.panicked;
        println!(
            "{:<44} {:>10} {:>10} {:>10} {:>7}",
            target.name, c.inputs, c.decoded, rejected, c.panicked
        );
    }
    let panics: u64 = counts.iter().map(|c| c.panicked).sum();
    assert_eq!(panics, 0, "{panics} inputs panicked (printed above)");
}
