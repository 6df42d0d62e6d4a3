//! The node's once-a-second health report on `/diagnostics`.

use std::time::{Duration, Instant};

use super::shared::Shared;
use crate::ros::messages::{DiagnosticArray, DiagnosticStatus, Header, KeyValue, Time};

/// Who the diagnostics status is about: its name and hardware.
pub(super) struct StatusIdentity {
    /// `<fully qualified node name>: empowerment`.
    pub(super) name: String,
    /// The robot, as its URDF names it.
    pub(super) hardware_id: String,
}

/// The once-a-second health report, from the inputs and counts `shared` holds (its problem and
/// time jump are taken: each is reported once).
pub(super) fn report(shared: &Shared, status: &StatusIdentity, stamp: Time) -> DiagnosticArray {
    let mut latest = shared.latest();
    let age = |t: Option<Instant>| t.map(|t| t.elapsed().as_secs_f64());
    let odom_age = age(latest.odom.as_ref().map(|(_, t)| *t));
    let scan_age = age(latest.last_scan);
    let timeout = shared.timeout().as_secs_f64();
    let fresh = |a: Option<f64>| a.is_some_and(|a| a <= timeout);
    let jump = latest.time_jump.take();
    let (level, message) = if let Some(rival) = &latest.rival {
        (
            DiagnosticStatus::ERROR,
            jump.map_or_else(|| rival.clone(), |jump| format!("{rival}; {jump}")),
        )
    } else if let Some(clash) = &latest.clash {
        (
            DiagnosticStatus::WARN,
            jump.map_or_else(|| clash.clone(), |jump| format!("{clash}; {jump}")),
        )
    } else if !fresh(odom_age) || !fresh(scan_age) {
        let stale = "inputs stale: no score";
        (
            DiagnosticStatus::STALE,
            jump.map_or_else(|| stale.to_owned(), |jump| format!("{stale}; {jump}")),
        )
    } else if let Some(jump) = jump {
        (DiagnosticStatus::WARN, jump)
    } else if let Some(problem) = latest.last_problem.take() {
        (DiagnosticStatus::WARN, problem)
    } else if latest.last_scan_unwatched {
        (
            DiagnosticStatus::OK,
            "no subscriber to the scores: scans not scored".to_owned(),
        )
    } else {
        (DiagnosticStatus::OK, "scoring".to_owned())
    };
    let show = |a: Option<f64>| a.map_or("never".to_owned(), |a| format!("{a:.3}"));
    let (score, valid, elapsed) = latest
        .last_score
        .unwrap_or((f64::NAN, false, Duration::ZERO));
    let values = [
        ("odometry_age_s", show(odom_age)),
        ("scan_age_s", show(scan_age)),
        (
            "last_empowerment",
            if score.is_finite() {
                format!("{score:.4}")
            } else {
                "none".into()
            },
        ),
        ("last_valid", valid.to_string()),
        (
            "evaluation_time_us",
            format!("{:.0}", elapsed.as_secs_f64() * 1e6),
        ),
        ("scans_scored", latest.scored.to_string()),
        ("scans_skipped", latest.skipped.to_string()),
        ("scans_unwatched", latest.unwatched.to_string()),
        ("scans_stale", latest.stale.to_string()),
        ("inputs_rejected", latest.rejected.to_string()),
        ("time_jumps", latest.time_jumps.to_string()),
        ("markers_published", latest.markers_published.to_string()),
        ("requests_waiting", shared.requests.waiting().to_string()),
        ("requests_answered", latest.requests_answered.to_string()),
        ("requests_refused", latest.requests_refused.to_string()),
        ("replies_failed", latest.replies_failed.to_string()),
    ];
    // The newest cloud's counts, once clouds are scored: where a band or range drops too much.
    let cloud = latest.last_cloud.map(|c| {
        [
            ("cloud_points", c.points),
            ("cloud_points_used", c.used),
            ("cloud_points_outside_band", c.outside_band),
            ("cloud_points_out_of_range", c.out_of_range),
            ("cloud_points_not_finite", c.not_finite),
        ]
        .map(|(key, n)| (key, n.to_string()))
    });
    let values = values.into_iter().chain(cloud.into_iter().flatten());
    DiagnosticArray {
        header: Header {
            stamp,
            frame_id: String::new(),
        },
        status: vec![DiagnosticStatus {
            level,
            name: status.name.clone(),
            message,
            hardware_id: status.hardware_id.clone(),
            values: values
                .map(|(key, value)| KeyValue {
                    key: key.into(),
                    value,
                })
                .collect(),
        }],
    }
}
