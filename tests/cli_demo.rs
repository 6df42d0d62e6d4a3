//! `cstep demo` end to end: the node and a simulated robot over real DDS on localhost.

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

#[test]
fn the_husky_demo_drives_through_the_door_and_scores_lowest_in_it() {
    let dir = std::env::temp_dir().join(format!("cstep-demo-husky-{}", std::process::id()));
    let plot = dir.join("drive.svg");
    let output = Command::new(env!("CARGO_BIN_EXE_cstep"))
        .args(["demo", "--robot", "husky", "--plot"])
        .arg(&plot)
        .env("ROS_DOMAIN_ID", "118")
        .output()
        .expect("cstep runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("Husky (diff_drive)"), "{stdout}");
    // "scored N scans (V valid)": 101 sent over 10 s, every one clear of the pallets.
    let summary = stdout
        .lines()
        .find_map(|l| l.strip_prefix("scored "))
        .expect("a summary line");
    let numbers: Vec<usize> = summary
        .split(|c: char| !c.is_ascii_digit())
        .filter_map(|n| n.parse().ok())
        .collect();
    let (scored, valid) = (numbers[0], numbers[1]);
    assert!(scored >= 90, "only {scored} of 101 scans scored:\n{stdout}");
    assert_eq!(valid, scored, "{stdout}");
    // The lowest score is in the 1.4 m door between the stacks (x from 3 to 4 m) or as the
    // Husky drives into it, not in the open hall nor at the far corner.
    let lowest_x: f64 = stdout
        .lines()
        .find_map(|l| l.strip_prefix("lowest "))
        .and_then(|l| l.split("(x, y) = (").nth(1))
        .and_then(|l| l.split(',').next())
        .and_then(|x| x.trim().parse().ok())
        .expect("the lowest score's place");
    assert!((2.5..=4.0).contains(&lowest_x), "{stdout}");
    let svg = std::fs::read_to_string(&plot).expect("the plot was written");
    assert_eq!(svg.matches("<circle").count(), scored);
    assert_eq!(svg.matches("#800000").count(), 2, "both stacks drawn");
}
