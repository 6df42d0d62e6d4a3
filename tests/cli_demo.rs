//! `cstep demo` end to end: the node and the simulated drone over real DDS on localhost.

use std::process::Command;

#[test]
fn a_five_second_demo_scores_the_flight_and_writes_its_plot() {
    let dir = std::env::temp_dir().join(format!("cstep-demo-{}", std::process::id()));
    let plot = dir.join("flight.svg");
    let output = Command::new(env!("CARGO_BIN_EXE_cstep"))
        .args(["demo", "--duration", "5", "--plot"])
        .arg(&plot)
        // A domain of its own, away from the Python tests' 1–100.
        .env("ROS_DOMAIN_ID", "117")
        .output()
        .expect("cstep runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stdout}\n{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let scored: usize = stdout
        .lines()
        .find_map(|l| {
            l.strip_prefix("scored ")?
                .split_whitespace()
                .next()?
                .parse()
                .ok()
        })
        .expect("a summary line");
    assert!(scored >= 45, "only {scored} of 51 scans scored:\n{stdout}");
    let svg = std::fs::read_to_string(&plot).expect("the plot was written");
    assert_eq!(svg.matches("<circle").count(), scored);
    assert!(!svg.contains("NaN"));
}
