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
fn the_husky_demo_scores_the_door_and_the_corner_below_the_open_hall() {
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
    // The live table's rows: t, x, y, speed, empowerment, reward, latency. Driving at 1 m/s,
    // the Husky scores lower in the 1.4 m door between the stacks (x from 3 to 4 m) than in the
    // open hall before it, and lowest heading into the far corner at full speed, 1 m from both
    // walls; stopped at the goal it scores higher again.
    let rows: Vec<[f64; 4]> = stdout
        .lines()
        .filter_map(|l| {
            let cells: Vec<f64> = l
                .split_whitespace()
                .filter_map(|c| c.parse().ok())
                .collect();
            (l.trim_end().ends_with("ms") && cells.len() == 7)
                .then(|| [cells[1], cells[2], cells[3], cells[4]])
        })
        .collect();
    assert!(rows.len() >= 90, "{stdout}");
    let lowest = |keep: &dyn Fn(&[f64; 4]) -> bool| {
        let scores = rows.iter().filter(|r| keep(r)).map(|r| r[3]);
        scores.fold(f64::INFINITY, f64::min)
    };
    let highest = |keep: &dyn Fn(&[f64; 4]) -> bool| {
        let scores = rows.iter().filter(|r| keep(r)).map(|r| r[3]);
        scores.fold(f64::NEG_INFINITY, f64::max)
    };
    let open_hall = highest(&|r| r[0] <= 1.5 && r[2] > 0.9);
    let door = lowest(&|r| (3.0..=4.0).contains(&r[0]));
    let corner = lowest(&|r| r[0] >= 7.5 && r[2] > 0.9);
    let stopped = highest(&|r| r[2] == 0.0);
    assert!(
        door < open_hall - 0.1,
        "door {door}, open hall {open_hall}\n{stdout}"
    );
    assert!(corner < door && corner < stopped - 0.5, "{stdout}");
    let svg = std::fs::read_to_string(&plot).expect("the plot was written");
    assert_eq!(svg.matches("<circle").count(), scored);
    assert_eq!(svg.matches("#800000").count(), 2, "both stacks drawn");
}
