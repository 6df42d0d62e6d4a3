//! `cstep node` refusing what it cannot run: one clear line and a non-zero exit before it joins
//! a DDS domain, never a panic or an abort.

mod common;

use std::process::{Command, Output};

fn node(ros_args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cstep"))
        .arg("node")
        .arg("--ros-args")
        .args(ros_args)
        // Private and local, should a regression let it start.
        .env("ROS_DOMAIN_ID", "231")
        .env("ROS_AUTOMATIC_DISCOVERY_RANGE", "OFF")
        .output()
        .expect("cstep runs")
}

/// Asserts a failure (exit 1) with exactly one line on stderr containing `words`.
fn assert_refused(output: &Output, words: &str) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(stderr.contains(words), "says {words}: {stderr}");
}

#[test]
fn a_configuration_beyond_the_memory_budget_is_refused_at_start() {
    // A regression: this once validated, and the node died on its first request.
    assert_refused(
        &node(&["-p", "trajectories:=100000", "-p", "steps:=10000"]),
        "command line: 'trajectories' × 'steps' (100000 × 10000, 2 command axes) needs 7629 MiB \
         of control samples, more than the 256 MiB an evaluation may allocate",
    );
}

#[test]
fn a_parameters_file_that_never_ends_is_refused_at_start() {
    // A regression: once read until memory ran out (/dev/zero) or blocked forever (a FIFO).
    assert_refused(
        &node(&["--params-file", "/dev/zero"]),
        "/dev/zero: cannot read the file: it is a character device, not a regular file",
    );
    let fifo = std::env::temp_dir().join(format!("cstep-node-params-{}.fifo", std::process::id()));
    common::make_fifo(&fifo);
    let fifo_arg = fifo.display().to_string();
    assert_refused(&node(&["--params-file", &fifo_arg]), "it is a FIFO");
    std::fs::remove_file(&fifo).unwrap();
}

#[test]
fn remaps_that_put_two_of_its_ports_on_one_name_are_refused() {
    // Regression: each of these was accepted without a word.
    for (args, words) in [
        (
            "cstep/reward:=cstep/empowerment",
            "topic /cstep/empowerment: the empowerment publisher (cstep_msgs/msg/Empowerment) \
             and the reward publisher (cstep_msgs/msg/EmpoweredReward) both resolve to it (a \
             topic carries one message type); give each its own name",
        ),
        (
            "cstep/evaluate_batch:=cstep/evaluate",
            "service /cstep/evaluate: the evaluate service (cstep_msgs/srv/Evaluate) and the \
             evaluate_batch service (cstep_msgs/srv/EvaluateBatch) both resolve to it",
        ),
        (
            "scan:=cstep/empowerment",
            "topic /cstep/empowerment: the empowerment publisher (cstep_msgs/msg/Empowerment) \
             and the scan subscription (sensor_msgs/msg/LaserScan) both resolve to it (the node \
             would read its own output)",
        ),
        (
            "odom:=/diagnostics",
            "topic /diagnostics: the diagnostics publisher (diagnostic_msgs/msg/DiagnosticArray) \
             and the odometry subscription (nav_msgs/msg/Odometry) both resolve to it (the node \
             would read its own output)",
        ),
    ] {
        assert_refused(&node(&["-r", args]), words);
    }
}

#[test]
fn a_name_longer_than_rcl_allows_is_refused_quoting_only_its_start() {
    // Regression: a 60 000-character name was accepted (rcl refuses over 247).
    let rule = format!("scan:={}", "a".repeat(60_000));
    let out = node(&["-r", &rule]);
    assert_refused(
        &out,
        "… (60001 characters)\" has 60001 characters, more than the 247 rcl allows in a topic \
         or service name",
    );
    assert!(
        out.stderr.len() < 400,
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
