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
