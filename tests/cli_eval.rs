//! `cstep eval` end to end through the binary: valid output, and one clear line (never a panic)
//! for every kind of bad input.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use cstep::demo::arena::PAPER_WORLD;
use cstep::demo::scene::Scene;
use cstep::ros::messages::{LaserScan, Odometry};
use nalgebra::{UnitQuaternion, Vector2};
use serde_json::Value;

fn workdir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cstep-cli-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn config() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("config/cstep.yaml")
}

fn corridor_scan() -> LaserScan {
    let scan = Scene::corridor(2.0, 20.0).scan(
        Vector2::new(0.0, 0.2),
        &UnitQuaternion::identity(),
        &PAPER_WORLD.lidar,
    );
    LaserScan {
        angle_min: scan.angle_min as f32,
        angle_max: (scan.angle_min + scan.angle_increment * (scan.ranges.len() - 1) as f64) as f32,
        angle_increment: scan.angle_increment as f32,
        range_min: scan.range_min as f32,
        range_max: scan.range_max as f32,
        ranges: scan.ranges,
        ..Default::default()
    }
}

fn odometry() -> Odometry {
    let mut odom = Odometry::default();
    odom.header.frame_id = "odom".into();
    odom.pose.pose.position.y = 0.2;
    odom.pose.pose.position.z = 1.0;
    odom.twist.twist.linear.x = 0.5;
    odom
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Writes the valid odometry and the corridor scan into `dir`; their paths.
fn write_valid_inputs(dir: &Path) -> (PathBuf, PathBuf) {
    let odom = write(
        dir,
        "odom.json",
        &serde_json::to_string(&odometry()).unwrap(),
    );
    let scan = write(
        dir,
        "scan.json",
        &serde_json::to_string(&corridor_scan()).unwrap(),
    );
    (odom, scan)
}

fn eval(odom: &Path, scan: &Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cstep"))
        .arg("eval")
        .arg("--config")
        .arg(config())
        .arg("--odom")
        .arg(odom)
        .arg("--scan")
        .arg(scan)
        .args(extra)
        .output()
        .expect("cstep runs")
}

fn json_of(output: &Output) -> Value {
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).expect("one JSON object")
}

/// Asserts a failure with one line on stderr naming `file` and containing `words`, no panic.
fn assert_clear_error(output: &Output, file: &str, words: &str) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "should fail: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(stderr.contains(file), "names {file}: {stderr}");
    assert!(stderr.contains(words), "says {words}: {stderr}");
}

#[test]
fn json_output_has_every_message_field_and_finite_values() {
    let dir = workdir("ok");
    let (odom, scan) = write_valid_inputs(&dir);
    let out = json_of(&eval(
        &odom,
        &scan,
        &["--format", "json", "--goal", "3,0.2,1"],
    ));
    for field in [
        "header",
        "empowerment",
        "reachable_volume",
        "terminal_volume",
        "free_volume",
        "safety_coefficient",
        "horizon",
        "num_trajectories",
        "num_colliding",
        "valid",
        "status",
        "reward",
        "task_reward",
    ] {
        assert!(out.get(field).is_some(), "missing {field} in {out}");
    }
    assert_eq!(out["valid"], true);
    assert_eq!(out["num_trajectories"], 150);
    assert_eq!(out["header"]["frame_id"], "odom");
    let task = out["task_reward"].as_f64().unwrap();
    assert!((task - (-3.0f64).exp()).abs() < 1e-9, "{task}");
    let (e, reward) = (
        out["empowerment"].as_f64().unwrap(),
        out["reward"].as_f64().unwrap(),
    );
    assert!(e.is_finite() && reward.is_finite());
    assert!((reward - task * (1.0f64.ln() + e)).abs() < 1e-9);
    // The same input and seed give the same answer; -p reaches the estimator.
    let again = json_of(&eval(
        &odom,
        &scan,
        &["--format", "json", "--goal", "3,0.2,1"],
    ));
    assert_eq!(out, again);
    let cautious = json_of(&eval(
        &odom,
        &scan,
        &["--format", "json", "-p", "safety_coefficient:=0.5"],
    ));
    assert_eq!(cautious["safety_coefficient"], 0.5);
    assert!((cautious["empowerment"].as_f64().unwrap() - e).abs() < 1e-12);
    let text = eval(&odom, &scan, &[]);
    assert!(String::from_utf8_lossy(&text.stdout).contains("empowerment"));
}

#[test]
fn rosbridge_nulls_in_ranges_are_accepted() {
    let dir = workdir("nulls");
    let odom = write(
        &dir,
        "odom.json",
        r#"{"pose":{"pose":{"position":{"x":0,"y":0,"z":1}}}}"#,
    );
    let mut scan: Value = serde_json::to_value(corridor_scan()).unwrap();
    scan["ranges"][0] = Value::Null;
    let scan = write(&dir, "scan.json", &scan.to_string());
    let out = json_of(&eval(&odom, &scan, &["--format", "json"]));
    assert_eq!(out["valid"], true);
}

#[test]
fn malformed_inputs_fail_with_one_line_naming_file_and_field() {
    let dir = workdir("bad");
    let (good_odom, good_scan) = write_valid_inputs(&dir);

    let broken = write(&dir, "broken.json", "{\"ranges\": [1.0, 2.0");
    assert_clear_error(
        &eval(&good_odom, &broken, &[]),
        "broken.json",
        "not a valid message",
    );

    let mut short = corridor_scan();
    short.ranges.truncate(100);
    let short = write(&dir, "short.json", &serde_json::to_string(&short).unwrap());
    assert_clear_error(
        &eval(&good_odom, &short, &[]),
        "short.json",
        "ranges: has 100 values",
    );

    let mut flat = corridor_scan();
    flat.angle_increment = 0.0;
    let flat = write(&dir, "flat.json", &serde_json::to_string(&flat).unwrap());
    assert_clear_error(
        &eval(&good_odom, &flat, &[]),
        "flat.json",
        "angle_increment",
    );

    let mut zero = odometry();
    zero.pose.pose.orientation.w = 0.0;
    let zero = write(&dir, "zero.json", &serde_json::to_string(&zero).unwrap());
    assert_clear_error(
        &eval(&zero, &good_scan, &[]),
        "zero.json",
        "zero quaternion",
    );

    let nan = write(
        &dir,
        "nan.json",
        r#"{"pose":{"pose":{"position":{"x":"nan"}}}}"#,
    );
    assert_clear_error(
        &eval(&nan, &good_scan, &[]),
        "nan.json",
        "not a valid message",
    );

    // Finite in f64 but physically meaningless: rejected, naming field and value.
    let mut fast = odometry();
    fast.twist.twist.linear.x = 1e39;
    let fast = write(&dir, "fast.json", &serde_json::to_string(&fast).unwrap());
    assert_clear_error(
        &eval(&fast, &good_scan, &[]),
        "fast.json",
        "twist.twist.linear: (1e39, 0.0, 0.0)",
    );
    let mut huge_q = odometry();
    huge_q.pose.pose.orientation.x = 1e155;
    let huge_q = write(
        &dir,
        "huge_q.json",
        &serde_json::to_string(&huge_q).unwrap(),
    );
    assert_clear_error(
        &eval(&huge_q, &good_scan, &[]),
        "huge_q.json",
        "pose.pose.orientation: is not a rotation",
    );

    // A regression: `[]` (and any non-object) was once read as the default message, a robot
    // at rest at the origin.
    for (name, text, kind) in [
        ("array.json", "[]", "an array"),
        ("number.json", " 3\n", "a number"),
        ("null.json", "null", "null"),
    ] {
        let file = write(&dir, name, text);
        let words = format!("not a valid message: expected a JSON object, got {kind}");
        assert_clear_error(&eval(&file, &good_scan, &[]), name, &words);
        assert_clear_error(&eval(&good_odom, &file, &[]), name, &words);
    }

    // A regression: narrowed to float32 first, this was once reported as "got inf".
    let mut wide = serde_json::to_value(corridor_scan()).unwrap();
    wide["angle_increment"] = serde_json::json!(1e300);
    let wide = write(&dir, "wide.json", &wide.to_string());
    assert_clear_error(
        &eval(&good_odom, &wide, &[]),
        "wide.json",
        "angle_increment: 1e300 does not fit the message's float32",
    );

    let missing = dir.join("missing.json");
    assert_clear_error(
        &eval(&missing, &good_scan, &[]),
        "missing.json",
        "cannot read",
    );

    assert_clear_error(
        &eval(&good_odom, &good_scan, &["-p", "horizon:=-2"]),
        "command line",
        "'horizon' must be a positive number",
    );
    // Validates, but its control sample would take 7.5 GiB: refused before any evaluation
    // (it once got through, and the allocator aborted the process, exit 134).
    assert_clear_error(
        &eval(
            &good_odom,
            &good_scan,
            &["-p", "trajectories:=100000", "-p", "steps:=10000"],
        ),
        "command line",
        "(100000 × 10000, 2 command axes) needs 7629 MiB of control samples, more than the \
         256 MiB an evaluation may allocate",
    );
    assert_clear_error(
        &eval(&good_odom, &good_scan, &["--goal", "1,x"]),
        "--goal",
        "X,Y[,Z]",
    );
    // The goal goes through the node's checks: finite, within ±1e7 m.
    assert_clear_error(
        &eval(&good_odom, &good_scan, &["--goal=nan,0"]),
        "--goal",
        "goal: must be finite, got (NaN, 0.0, 1.0)",
    );
    assert_clear_error(
        &eval(&good_odom, &good_scan, &["--goal=1,2e7,1"]),
        "--goal",
        "(1.0, 20000000.0, 1.0) m is beyond",
    );

    let urdf = write(
        &dir,
        "bad.urdf",
        "<robot name=\"x\"><link name=\"base\"/></robot>",
    );
    let p = format!("robot_description:={}", urdf.display());
    let out = eval(&good_odom, &good_scan, &["-p", &p]);
    assert_clear_error(&out, "bad.urdf", "");
}

#[test]
fn misspelt_fields_are_refused_with_their_path_and_the_field_meant() {
    // Regression: "pos" for "position" and "linaer" for "linear" were silently dropped
    // and the odometry scored as a robot at the origin at rest, exit code 0.
    let dir = workdir("misspelt");
    let (good_odom, good_scan) = write_valid_inputs(&dir);
    let odom = write(
        &dir,
        "typo_odom.json",
        r#"{"pose": {"pose": {"pos": {"x": 1.0, "y": 0.2, "z": 1.0}}},
            "twist": {"twist": {"linaer": {"x": 0.5}}}}"#,
    );
    assert_clear_error(
        &eval(&odom, &good_scan, &[]),
        "typo_odom.json",
        "not a valid message: pose.pose.pos: unknown field, did you mean `position`?",
    );
    let odom = write(
        &dir,
        "typo_twist.json",
        r#"{"twist": {"twist": {"linaer": {"x": 0.5}}}}"#,
    );
    assert_clear_error(
        &eval(&odom, &good_scan, &[]),
        "typo_twist.json",
        "twist.twist.linaer: unknown field, did you mean `linear`?",
    );
    let mut scan = serde_json::to_value(corridor_scan()).unwrap();
    let ranges = scan.as_object_mut().unwrap().remove("ranges").unwrap();
    scan["rangs"] = ranges;
    let scan = write(&dir, "typo_scan.json", &scan.to_string());
    assert_clear_error(
        &eval(&good_odom, &scan, &[]),
        "typo_scan.json",
        "rangs: unknown field, did you mean `ranges`?",
    );
    // Fields left out still take their ROS defaults (orientation w = 1).
    let partial = write(
        &dir,
        "partial.json",
        r#"{"pose": {"pose": {"position": {"y": 0.2, "z": 1.0}}}}"#,
    );
    let out = json_of(&eval(&partial, &good_scan, &["--format", "json"]));
    assert_eq!(out["valid"], true, "{out}");
}

#[test]
fn endless_special_and_oversized_input_files_are_refused_naming_them() {
    // A regression: /dev/zero as any input was once read until memory ran out, a FIFO blocked
    // forever. Each is refused in one line naming the path and what it is.
    let dir = workdir("special");
    let (odom, scan) = write_valid_inputs(&dir);
    let device = "it is a character device, not a regular file";
    let zero = Path::new("/dev/zero");
    assert_clear_error(&eval(zero, &scan, &[]), "/dev/zero", device);
    assert_clear_error(
        &eval(&odom, Path::new("/dev/urandom"), &[]),
        "/dev/urandom",
        device,
    );
    let urdf = ["-p", "robot_description:=/dev/zero"];
    assert_clear_error(&eval(&odom, &scan, &urdf), "/dev/zero", device);
    let out = Command::new(env!("CARGO_BIN_EXE_cstep"))
        .args(["eval", "--config", "/dev/zero", "--odom"])
        .arg(&odom)
        .arg("--scan")
        .arg(&scan)
        .output()
        .unwrap();
    assert_clear_error(&out, "/dev/zero", device);

    let fifo = dir.join("scan.fifo");
    common::make_fifo(&fifo);
    assert_clear_error(&eval(&odom, &fifo, &[]), "scan.fifo", "it is a FIFO");

    let large = dir.join("large.json");
    std::fs::File::create(&large)
        .unwrap()
        .set_len(cstep::input::file::MAX_INPUT_FILE_BYTES + 1)
        .unwrap();
    assert_clear_error(
        &eval(&large, &scan, &[]),
        "large.json",
        "it holds more than 16 MiB, the most an input file may",
    );
}

#[test]
fn degenerate_but_well_formed_inputs_answer_valid_false() {
    let dir = workdir("degenerate");
    let odom = write(
        &dir,
        "odom.json",
        &serde_json::to_string(&odometry()).unwrap(),
    );
    let mut empty = corridor_scan();
    empty.ranges.clear();
    let empty = write(&dir, "empty.json", &serde_json::to_string(&empty).unwrap());
    let out = json_of(&eval(&odom, &empty, &["--format", "json"]));
    assert_eq!(out["valid"], false);
    assert_eq!(out["status"], "scan has no beams");
    assert!(out["empowerment"].as_f64().unwrap().is_finite());

    let mut blind = corridor_scan();
    blind.ranges.iter_mut().for_each(|r| *r = f32::NAN);
    let blind = write(
        &dir,
        "blind.json",
        &serde_json::to_string(&blind)
            .unwrap()
            .replace("null", "\"nan\""),
    );
    let out = json_of(&eval(&odom, &blind, &["--format", "json"]));
    assert_eq!(out["valid"], false);
    assert_eq!(out["status"], "scan has no valid beams");
}
