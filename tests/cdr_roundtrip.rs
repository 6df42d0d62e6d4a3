//! The Rust message mirrors against the DDS wire format as real rclpy writes it.
//!
//! `tests/data/cdr/*.cdr` are `rclpy.serialization.serialize_message` output (ROS 2 Jazzy, Fast
//! DDS), made by `tests/data/cdr/generate.py` and checked byte for byte against fresh rclpy
//! output by `tests/python/test_cdr_fixtures.py`. Each file is a 4-byte encapsulation header
//! (`00 01 00 00`: plain CDR, little-endian) and the CDR body, whose alignment padding is zero
//! (Fast CDR leaves it uninitialised; the generator zeroes it). Here each body is decoded with
//! `cdr-encoding` (the codec ros2-client uses through rustdds), its values checked against those
//! the generator set, re-encoded, and compared with the file byte for byte.

use std::f64::consts::PI;
use std::path::Path;

use approx::assert_relative_eq;
use byteorder::LittleEndian;
use cstep::ros::messages::point_cloud::cloud_points;
use cstep::ros::messages::{
    ColorRGBA, CompressedImage, DiagnosticArray, Duration, EmpoweredReward, Empowerment,
    EvaluateBatchRequest, EvaluateBatchResponse, EvaluateRequest, EvaluateResponse, Header,
    LaserScan, Marker, MarkerArray, MeshFile, Odometry, Point, PointCloud2, Pose, PoseStamped,
    Quaternion, SpeedLimit, Time, UVCoordinate, Vector3,
};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// The encapsulation header rclpy writes before the CDR body: CDR_LE, options 0.
const CDR_LE: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Every fixture file; `every_fixture_file_is_tested` keeps this list complete.
const FIXTURES: [&str; 16] = [
    "diagnostic_array",
    "empowered_reward",
    "empowerment",
    "evaluate_batch_request",
    "evaluate_batch_response",
    "evaluate_request",
    "evaluate_response",
    "header",
    "laser_scan",
    "laser_scan_empty",
    "marker_array",
    "odometry",
    "point_cloud2",
    "point_cloud2_big_endian",
    "pose_stamped",
    "speed_limit",
];

fn fixture_dir() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/cdr"))
}

/// The CDR body of fixture `name` (its encapsulation header checked and removed).
fn body(name: &str) -> Vec<u8> {
    let path = fixture_dir().join(format!("{name}.cdr"));
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(bytes[..4], CDR_LE, "{name}: encapsulation header");
    bytes[4..].to_vec()
}

/// Decodes fixture `name` as a `T`, requiring every byte to be used, and checks that
/// re-encoding the value gives the same bytes.
fn decode<T: DeserializeOwned + Serialize>(name: &str) -> T {
    let body = body(name);
    let (value, used) = cdr_encoding::from_bytes::<T, LittleEndian>(&body)
        .unwrap_or_else(|e| panic!("{name}: decoding failed: {e}"));
    assert_eq!(
        used,
        body.len(),
        "{name}: decoded {used} of {} bytes",
        body.len()
    );
    let again = cdr_encoding::to_vec::<T, LittleEndian>(&value).unwrap();
    assert_eq!(
        again, body,
        "{name}: re-encoding differs from rclpy's bytes"
    );
    value
}

fn stamp(sec: i32, nanosec: u32) -> Time {
    Time { sec, nanosec }
}

fn header(sec: i32, nanosec: u32, frame_id: &str) -> Header {
    Header {
        stamp: stamp(sec, nanosec),
        frame_id: frame_id.to_string(),
    }
}

/// The odometry `generate.py` builds (`odometry()`).
fn check_odometry(odom: &Odometry) {
    assert_eq!(odom.header, header(42, 500_000_000, "odom"));
    assert_eq!(odom.child_frame_id, "base_link");
    let p = odom.pose.pose.position;
    assert_eq!((p.x, p.y, p.z), (1.25, -0.1, 0.75));
    let q = odom.pose.pose.orientation;
    assert_eq!((q.x, q.y), (0.0, 0.0));
    assert_relative_eq!(q.z, (PI / 8.0).sin(), max_relative = 1e-15);
    assert_relative_eq!(q.w, (PI / 8.0).cos(), max_relative = 1e-15);
    for (i, c) in odom.pose.covariance.iter().enumerate() {
        assert_eq!(*c, 0.01 * i as f64, "pose covariance {i}");
    }
    let t = odom.twist.twist;
    assert_eq!((t.linear.x, t.linear.y, t.linear.z), (1.0, -0.5, 0.05));
    assert_eq!((t.angular.x, t.angular.y, t.angular.z), (0.0, 0.0, 0.3));
    for (i, c) in odom.twist.covariance.iter().enumerate() {
        assert_eq!(*c, -(i as f64), "twist covariance {i}");
    }
}

/// The scan `generate.py` builds (`laser_scan()`): REP 117 non-finite ranges included.
fn check_laser_scan(scan: &LaserScan) {
    assert_eq!(scan.header, header(42, 499_000_000, "laser"));
    assert_eq!(scan.angle_min, -PI as f32);
    assert_eq!(scan.angle_max, (PI - 2.0 * PI / 8.0) as f32);
    assert_eq!(scan.angle_increment, (2.0 * PI / 8.0) as f32);
    assert_eq!(scan.time_increment, 1.0e-4_f64 as f32);
    assert_eq!(scan.scan_time, 0.025_f64 as f32);
    assert_eq!(scan.range_min, 0.05_f64 as f32);
    assert_eq!(scan.range_max, 3.5);
    let r = &scan.ranges;
    assert_eq!(r.len(), 8);
    assert_eq!(r[0], 0.5);
    assert_eq!(r[1], f32::INFINITY, "+inf: no return");
    assert!(r[2].is_nan(), "NaN: invalid beam");
    assert_eq!(r[3], f32::NEG_INFINITY, "-inf: too close");
    assert_eq!(&r[4..], &[1.25, 3.0, 0.1_f64 as f32, 2.75]);
    assert_eq!(
        scan.intensities,
        vec![100.0, 0.0, 0.0, 0.0, 57.5, 12.0, 255.0, 1.5]
    );
}

#[test]
fn every_fixture_file_is_tested() {
    let mut found: Vec<String> = std::fs::read_dir(fixture_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "cdr"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    found.sort();
    assert_eq!(found, FIXTURES);
}

#[test]
fn header_round_trips() {
    // "base_scan" + NUL is 10 bytes: a string whose length is not a multiple of 4.
    let h: Header = decode("header");
    assert_eq!(h, header(1_700_000_123, 456_789_012, "base_scan"));
}

#[test]
fn pose_stamped_round_trips() {
    let goal: PoseStamped = decode("pose_stamped");
    assert_eq!(goal.header, header(7, 1, "map"));
    let p = goal.pose.position;
    assert_eq!((p.x, p.y, p.z), (3.9, -0.3, 1.0));
    assert_eq!(goal.pose.orientation.w, 1.0);
}

#[test]
fn diagnostic_array_round_trips() {
    let d: DiagnosticArray = decode("diagnostic_array");
    assert_eq!(d.header, header(9, 0, ""));
    let status = &d.status[0];
    assert_eq!(status.level, 3);
    assert_eq!(status.name, "cstep: empowerment");
    assert_eq!(status.message, "inputs stale: no score");
    let values: Vec<(&str, &str)> = status
        .values
        .iter()
        .map(|kv| (kv.key.as_str(), kv.value.as_str()))
        .collect();
    assert_eq!(
        values,
        [("scans_scored", "12"), ("odometry_age_s", "never")]
    );
}

#[test]
fn odometry_round_trips() {
    check_odometry(&decode::<Odometry>("odometry"));
}

#[test]
fn laser_scan_with_inf_nan_and_negative_inf_round_trips() {
    // CDR is a binary format: `lenient_floats` (JSON's null/"inf" stand-ins) must pass the
    // f32 sequence through untouched, NaN bits included (the re-encoding check covers them).
    check_laser_scan(&decode::<LaserScan>("laser_scan"));
}

#[test]
fn point_clouds_in_either_byte_order_round_trip_and_give_their_points() {
    // tests/data/cdr/generate.py's CLOUD_POINTS (x, y, z; intensity is not read).
    let expected = [[1.5, 0.0, 0.1], [-0.5, 2.25, -0.05], [f32::NAN; 3]];
    for (name, big_endian) in [("point_cloud2", false), ("point_cloud2_big_endian", true)] {
        let cloud: PointCloud2 = decode(name);
        assert_eq!(cloud.header, header(7, 250_000_000, "lidar"), "{name}");
        assert_eq!((cloud.height, cloud.width, cloud.point_step), (1, 3, 16));
        assert_eq!((cloud.is_bigendian, cloud.is_dense), (big_endian, false));
        let names: Vec<&str> = cloud.fields.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["x", "y", "z", "intensity"]);
        let points = cloud_points(&cloud, 1000).unwrap();
        assert_eq!(points.len(), 3, "{name}");
        for (got, want) in points.iter().flatten().zip(expected.iter().flatten()) {
            assert!(
                got == want || (got.is_nan() && want.is_nan()),
                "{name}: {points:?}"
            );
        }
    }
}

#[test]
fn empty_laser_scan_round_trips() {
    let scan: LaserScan = decode("laser_scan_empty");
    assert_eq!(scan, LaserScan::default());
}

#[test]
fn empowerment_round_trips() {
    let e: Empowerment = decode("empowerment");
    assert_eq!(e.header, header(42, 499_000_000, "odom"));
    assert_relative_eq!(e.empowerment, 3.25_f64.ln(), max_relative = 1e-15);
    assert_eq!(
        (e.reachable_volume, e.terminal_volume, e.free_volume),
        (4.0, 0.75, 3.25)
    );
    assert_eq!((e.safety_coefficient, e.horizon), (0.5, 1.0));
    assert_eq!((e.num_trajectories, e.num_colliding), (150, 27));
    assert!(e.valid);
    assert_eq!(e.status, "ok");
}

#[test]
fn nav2_speed_limit_round_trips() {
    // What Nav2's controller server receives: rclpy's bytes for the test-only nav2_msgs, the
    // message definition Nav2 ships.
    let limit: SpeedLimit = decode("speed_limit");
    assert_eq!(
        limit,
        SpeedLimit {
            header: header(5001, 250_000_000, "odom"),
            percentage: true,
            speed_limit: 79.375,
        }
    );
}

#[test]
fn empowered_reward_round_trips() {
    let r: EmpoweredReward = decode("empowered_reward");
    assert_eq!(r.header, header(42, 499_000_000, "odom"));
    let task = (-2.0_f64).exp();
    let term = (0.5_f64 * 3.25).ln();
    assert_relative_eq!(r.task_reward, task, max_relative = 1e-15);
    assert_relative_eq!(r.empowerment_term, term, max_relative = 1e-15);
    assert_relative_eq!(r.reward, task * term, max_relative = 1e-15);
    assert_eq!(r.safety_coefficient, 0.5);
    assert!(r.valid);
}

#[test]
fn evaluate_request_round_trips() {
    let req: EvaluateRequest = decode("evaluate_request");
    check_odometry(&req.odom);
    check_laser_scan(&req.scan);
    assert_eq!(
        req.goal,
        Point {
            x: 4.0,
            y: 0.0,
            z: 1.0
        }
    );
    assert!(req.has_goal);
}

#[test]
fn evaluate_response_round_trips() {
    let res: EvaluateResponse = decode("evaluate_response");
    let floor = 1e-4_f64.ln();
    let e = &res.empowerment;
    assert_eq!(e.header, header(7, 1, "map"));
    assert_relative_eq!(e.empowerment, floor, max_relative = 1e-15);
    assert_eq!(
        (e.reachable_volume, e.terminal_volume, e.free_volume),
        (2.5, 2.5, 0.0)
    );
    assert_eq!((e.safety_coefficient, e.horizon), (1.0, 1.5));
    assert_eq!((e.num_trajectories, e.num_colliding), (2000, 2000));
    assert!(!e.valid);
    assert_eq!(e.status, "every trajectory collides");
    let r = &res.reward;
    assert_eq!(r.header, e.header);
    assert_relative_eq!(r.reward, floor, max_relative = 1e-15);
    assert_relative_eq!(r.empowerment_term, floor, max_relative = 1e-15);
    assert_eq!((r.task_reward, r.safety_coefficient), (1.0, 1.0));
    assert!(!r.valid);
}

#[test]
fn evaluate_batch_request_round_trips() {
    let req: EvaluateBatchRequest = decode("evaluate_batch_request");
    assert_eq!((req.odom.len(), req.scan.len()), (2, 2));
    check_odometry(&req.odom[0]);
    assert_eq!(req.odom[1].pose.pose.position.x, -2.5);
    check_laser_scan(&req.scan[0]);
    assert_eq!(req.scan[1], LaserScan::default());
    let goal = Point {
        x: 4.0,
        y: 0.0,
        z: 1.0,
    };
    assert_eq!(req.goal, [goal, Point::default()]);
    assert_eq!(req.has_goal, [true, false]);
    assert_eq!(req.in_collision, [false, true]);
}

#[test]
fn evaluate_batch_response_round_trips() {
    let res: EvaluateBatchResponse = decode("evaluate_batch_response");
    assert_eq!(res.empowerment[0], decode::<Empowerment>("empowerment"));
    assert_eq!(res.reward[0], decode::<EmpoweredReward>("empowered_reward"));
    let (e, r) = (&res.empowerment[1], &res.reward[1]);
    let floor = 1e-4_f64.ln();
    assert_relative_eq!(e.empowerment, floor, max_relative = 1e-15);
    assert_eq!((e.num_trajectories, e.num_colliding), (150, 150));
    assert_eq!(e.free_volume, 0.0);
    assert!(!e.valid && !r.valid);
    assert_eq!(e.status, "robot already in collision");
    assert_relative_eq!(r.reward, 0.5_f64.ln() + floor, max_relative = 1e-15);
    assert_eq!((r.task_reward, r.safety_coefficient), (1.0, 0.5));
}

#[test]
fn messages_built_in_rust_encode_to_rclpy_bytes() {
    // The other direction: a message made here, not decoded, is what rclpy expects on the wire.
    let h = header(1_700_000_123, 456_789_012, "base_scan");
    assert_eq!(
        cdr_encoding::to_vec::<_, LittleEndian>(&h).unwrap(),
        body("header")
    );
    let mut response = EvaluateResponse {
        empowerment: Empowerment {
            header: header(7, 1, "map"),
            empowerment: 0.0,
            reachable_volume: 2.5,
            terminal_volume: 2.5,
            free_volume: 0.0,
            safety_coefficient: 1.0,
            horizon: 1.5,
            num_trajectories: 2000,
            num_colliding: 2000,
            valid: false,
            status: "every trajectory collides".to_string(),
        },
        reward: EmpoweredReward {
            header: header(7, 1, "map"),
            reward: 0.0,
            task_reward: 1.0,
            empowerment_term: 0.0,
            safety_coefficient: 1.0,
            valid: false,
        },
    };
    // ln(1e-4), as Python's math.log computed it: take the transcendental value from the file.
    let decoded: EvaluateResponse = decode("evaluate_response");
    response.empowerment.empowerment = decoded.empowerment.empowerment;
    response.reward.reward = decoded.reward.reward;
    response.reward.empowerment_term = decoded.reward.empowerment_term;
    assert_eq!(response, decoded);
    assert_eq!(
        cdr_encoding::to_vec::<_, LittleEndian>(&response).unwrap(),
        body("evaluate_response")
    );
}

/// `rgba` as rclpy stores it: float32 channels.
fn color(r: f64, g: f64, b: f64, a: f64) -> ColorRGBA {
    ColorRGBA {
        r: r as f32,
        g: g as f32,
        b: b as f32,
        a: a as f32,
    }
}

#[test]
fn marker_array_with_every_humble_field_round_trips_and_builds_from_rust() {
    // Built here field by field, as `generate.py` builds it: equal after decoding, and the same
    // bytes when encoded, so every Marker field sits where RViz (rclpy, Fast DDS) expects it.
    let points = Marker {
        header: header(42, 499_000_000, "odom"),
        ns: "cstep/endpoints".into(),
        id: 0,
        kind: Marker::POINTS,
        action: Marker::ADD,
        scale: Vector3 {
            x: 0.05,
            y: 0.05,
            z: 0.0,
        },
        color: color(0.1, 0.8, 0.1, 1.0),
        lifetime: Duration {
            sec: 0,
            nanosec: 500_000_000,
        },
        points: vec![
            Point {
                x: 1.25,
                y: -0.5,
                z: 1.0,
            },
            Point {
                x: -2.0,
                y: 0.75,
                z: 1.125,
            },
        ],
        colors: vec![color(0.1, 0.8, 0.1, 1.0), color(0.9, 0.1, 0.1, 1.0)],
        ..Default::default()
    };
    let everything = Marker {
        header: header(-3, 7, "base"),
        ns: "all".into(),
        id: -17,
        kind: 11, // TRIANGLE_LIST
        action: Marker::DELETEALL,
        pose: Pose {
            position: Point {
                x: 3.0,
                y: 0.0,
                z: 0.0,
            },
            orientation: Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.0,
                w: 0.5,
            },
        },
        scale: Vector3 {
            x: 0.0,
            y: 0.0,
            z: 2.5,
        },
        color: color(0.2, 0.5, 1.0, 0.25),
        lifetime: Duration { sec: 2, nanosec: 1 },
        frame_locked: true,
        points: vec![Point {
            x: 0.5,
            y: 0.25,
            z: -1.0,
        }],
        colors: vec![],
        texture_resource: "file://t.png".into(),
        texture: CompressedImage {
            header: header(1, 2, "cam"),
            format: "png".into(),
            data: vec![137, 80, 78],
        },
        uv_coordinates: vec![UVCoordinate { u: 0.25, v: 0.75 }],
        text: "hi".into(),
        mesh_resource: "package://m.dae".into(),
        mesh_file: MeshFile {
            filename: "m.stl".into(),
            data: vec![1, 2, 3, 4, 5],
        },
        mesh_use_embedded_materials: true,
    };
    let built = MarkerArray {
        markers: vec![points, everything],
    };
    let decoded: MarkerArray = decode("marker_array");
    assert_eq!(decoded, built);
    assert_eq!(
        cdr_encoding::to_vec::<_, LittleEndian>(&built).unwrap(),
        body("marker_array")
    );
}
