//! `/cstep/markers`: what one evaluation saw, for RViz.
//!
//! Two markers per score, in the odometry frame and stamped like the score:
//! - `cstep/endpoints` (`POINTS`): every sampled trajectory's endpoint at the horizon, green when
//!   the trajectory stayed free, red when it collided (terminal);
//! - `cstep/hull` (`LINE_STRIP`): the closed outline of the convex hull of all endpoints,
//!   projected on the robot's horizontal plane — the reachable set the score measures.
//!
//! Endpoints in [`Rollout`] are relative to the robot with world-aligned axes, so each marker
//! point is the robot's position plus the endpoint. Non-finite endpoints are left out. A marker
//! with nothing to draw is sent as `DELETE`, so RViz drops the previous one.

use nalgebra::Vector3;

use crate::rollout::Rollout;
use crate::ros::messages::{
    ColorRGBA, Duration, Header, Marker, MarkerArray, Point, Pose, Vector3 as V3,
};
use crate::volume::planar_hull;

/// Namespace of the endpoint marker.
pub const ENDPOINTS_NS: &str = "cstep/endpoints";
/// Namespace of the hull outline marker.
pub const HULL_NS: &str = "cstep/hull";
/// Colour of an endpoint whose trajectory stayed free.
pub const FREE: ColorRGBA = ColorRGBA {
    r: 0.1,
    g: 0.8,
    b: 0.1,
    a: 1.0,
};
/// Colour of an endpoint whose trajectory collided.
pub const TERMINAL: ColorRGBA = ColorRGBA {
    r: 0.9,
    g: 0.1,
    b: 0.1,
    a: 1.0,
};
/// Colour of the hull outline.
pub const HULL: ColorRGBA = ColorRGBA {
    r: 0.2,
    g: 0.5,
    b: 1.0,
    a: 1.0,
};
/// Width and height of an endpoint dot, metres.
const POINT_SIZE: f64 = 0.05;
/// Width of the hull outline, metres.
const LINE_WIDTH: f64 = 0.02;

/// The markers of one evaluation from `robot` (odometry frame), in `header`'s frame and stamp;
/// they expire after `lifetime` seconds unless a newer score replaces them.
pub fn rollout_markers(
    header: &Header,
    robot: &Vector3<f64>,
    rollout: &Rollout,
    lifetime: f64,
) -> MarkerArray {
    let mut points = Vec::with_capacity(rollout.endpoints.len());
    let mut colors = Vec::with_capacity(rollout.endpoints.len());
    for (end, &terminal) in rollout.endpoints.iter().zip(&rollout.terminal) {
        let p = Point {
            x: robot.x + end[0],
            y: robot.y + end[1],
            z: robot.z + end[2],
        };
        if [p.x, p.y, p.z].iter().all(|v| v.is_finite()) {
            points.push(p);
            colors.push(if terminal { TERMINAL } else { FREE });
        }
    }
    let outline = hull_outline(&points, robot.z);
    let base = Marker {
        header: header.clone(),
        pose: Pose::default(),
        lifetime: Duration::from_seconds(lifetime),
        ..Default::default()
    };
    let endpoints = Marker {
        ns: ENDPOINTS_NS.into(),
        kind: Marker::POINTS,
        action: if points.is_empty() {
            Marker::DELETE
        } else {
            Marker::ADD
        },
        scale: V3 {
            x: POINT_SIZE,
            y: POINT_SIZE,
            z: 0.0,
        },
        color: FREE,
        points,
        colors,
        ..base.clone()
    };
    let hull = Marker {
        ns: HULL_NS.into(),
        kind: Marker::LINE_STRIP,
        action: if outline.is_empty() {
            Marker::DELETE
        } else {
            Marker::ADD
        },
        scale: V3 {
            x: LINE_WIDTH,
            y: 0.0,
            z: 0.0,
        },
        color: HULL,
        points: outline,
        ..base
    };
    MarkerArray {
        markers: vec![endpoints, hull],
    }
}

/// The convex hull of `points` seen from above, as a closed line (first point repeated last) at
/// height `z`; empty when the points span no area.
fn hull_outline(points: &[Point], z: f64) -> Vec<Point> {
    let cloud: Vec<[f64; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
    let Some(vertices) = planar_hull(&cloud) else {
        return Vec::new();
    };
    vertices
        .iter()
        .chain(vertices.first())
        .map(|v| Point {
            x: v[0],
            y: v[1],
            z,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros::messages::Time;

    fn header() -> Header {
        Header {
            stamp: Time {
                sec: 12,
                nanosec: 3,
            },
            frame_id: "odom".into(),
        }
    }

    #[test]
    fn endpoints_are_placed_around_the_robot_and_coloured_by_outcome() {
        let rollout = Rollout {
            endpoints: vec![
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [-1.0, 0.0, 0.1],
                [0.0, -1.0, 0.0],
                [0.2, 0.1, 0.0],
            ],
            terminal: vec![false, true, false, true, false],
        };
        let robot = Vector3::new(10.0, -2.0, 1.0);
        let array = rollout_markers(&header(), &robot, &rollout, 0.5);
        let [endpoints, hull] = &array.markers[..] else {
            panic!("two markers expected: {array:?}")
        };
        assert_eq!(endpoints.kind, Marker::POINTS);
        assert_eq!(
            (endpoints.action, endpoints.ns.as_str()),
            (Marker::ADD, ENDPOINTS_NS)
        );
        assert_eq!(endpoints.header, header());
        assert_eq!(
            endpoints.lifetime,
            Duration {
                sec: 0,
                nanosec: 500_000_000
            }
        );
        assert_eq!(endpoints.points.len(), 5);
        assert_eq!(
            endpoints.points[2],
            Point {
                x: 9.0,
                y: -2.0,
                z: 1.1
            }
        );
        let reds = endpoints.colors.iter().filter(|c| **c == TERMINAL).count();
        let greens = endpoints.colors.iter().filter(|c| **c == FREE).count();
        assert_eq!((reds, greens), (2, 3));

        assert_eq!((hull.kind, hull.action), (Marker::LINE_STRIP, Marker::ADD));
        // The four extreme points, closed: the interior point is not on the outline.
        assert_eq!(hull.points.len(), 5);
        assert_eq!(hull.points.first(), hull.points.last());
        assert!(hull.points.iter().all(|p| p.z == 1.0));
        assert!(!hull.points.iter().any(|p| p.x == 10.2));
    }

    #[test]
    fn non_finite_endpoints_are_dropped_and_empty_markers_are_deletions() {
        let rollout = Rollout {
            endpoints: vec![[f64::NAN, 0.0, 0.0], [1.0, 1.0, 0.0]],
            terminal: vec![false, true],
        };
        let array = rollout_markers(&header(), &Vector3::zeros(), &rollout, 1.0);
        assert_eq!(array.markers[0].points.len(), 1);
        assert_eq!(array.markers[0].colors, vec![TERMINAL]);
        assert_eq!(array.markers[1].action, Marker::DELETE);
        assert!(array.markers[1].points.is_empty());

        let array = rollout_markers(&header(), &Vector3::zeros(), &Rollout::default(), 1.0);
        assert!(array.markers.iter().all(|m| m.action == Marker::DELETE));
    }

    #[test]
    fn collinear_endpoints_have_no_outline() {
        let rollout = Rollout {
            endpoints: (0..5).map(|i| [i as f64, 0.0, 0.0]).collect(),
            terminal: vec![false; 5],
        };
        let array = rollout_markers(&header(), &Vector3::zeros(), &rollout, 1.0);
        assert_eq!(array.markers[1].action, Marker::DELETE);
    }
}
