//! A 3-D point cloud read as a 2-D scan, so that clouds get the scan's occupancy and its
//! conservative reading of unseen space.
//!
//! The points of a height band around the robot are binned by bearing in the world-aligned
//! frame and each bin keeps its nearest point's horizontal range — what ROS's
//! `pointcloud_to_laserscan` does. A bin of the sensor's field of view without a point in the
//! band reads as no return within range (free up to `range_max`, as `pointcloud_to_laserscan`
//! reads it: a LiDAR drops the points of beams that returned nothing); a bin outside the field
//! of view reads as invalid, so `unknown_space` decides it as it decides a scan's unseen
//! bearings. Binning by the world-aligned bearing after the attitude's full rotation keeps a
//! tilted sensor's points where they are; the scan it gives is therefore read in
//! [`crate::occupancy::ScanFrame::WorldAligned`].

use std::f64::consts::PI;

use nalgebra::{UnitQuaternion, Vector3};

use crate::occupancy::Scan;

/// Bearing bins of the scan a cloud becomes: 0.5° each, the occupancy's own bin width.
pub const CLOUD_BINS: usize = 720;

/// Which points of a cloud count, and how far the sensor sees.
#[derive(Debug, Clone, PartialEq)]
pub struct CloudOptions {
    /// Lowest and highest point that counts, metres above the robot's origin (world-aligned
    /// z, after the attitude's rotation): the band the robot's body sweeps.
    pub band: (f64, f64),
    /// Horizontal ranges below this are dropped (the robot's own body), metres.
    pub range_min: f64,
    /// Horizontal ranges beyond this are dropped; a bin without a point is free up to it,
    /// metres.
    pub range_max: f64,
    /// The sensor's horizontal field of view, radians, centred on the body's x axis; `2π` (or
    /// more) for a spinning LiDAR.
    pub field_of_view: f64,
}

/// How a node reads its point clouds: which points count, and the most it reads of one cloud
/// (a larger one is thinned evenly), which bounds the work a cloud costs.
#[derive(Debug, Clone, PartialEq)]
pub struct CloudInput {
    /// Which points count.
    pub options: CloudOptions,
    /// The most points read of one cloud.
    pub max_points: usize,
}

/// What a cloud held, for diagnostics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CloudSummary {
    /// Points read.
    pub points: usize,
    /// Points with a NaN or infinite coordinate (organised clouds mark missing returns so).
    pub not_finite: usize,
    /// Finite points above or below the band.
    pub outside_band: usize,
    /// Points in the band nearer than `range_min` or beyond `range_max`.
    pub out_of_range: usize,
    /// Points that became part of the scan.
    pub used: usize,
}

/// The scan a cloud becomes, and what the cloud held.
#[derive(Debug, Clone, PartialEq)]
pub struct CloudScan {
    /// The scan, in the world-aligned frame centred on the robot
    /// ([`crate::occupancy::ScanFrame::WorldAligned`]).
    pub scan: Scan,
    /// The cloud's counts.
    pub summary: CloudSummary,
}

impl CloudScan {
    /// Reads `points` (x, y, z in the robot's body frame, metres; the sensor at the body
    /// origin, as for a scan) taken at attitude `attitude` (body → world).
    pub fn from_points(
        points: impl IntoIterator<Item = [f32; 3]>,
        attitude: &UnitQuaternion<f64>,
        options: &CloudOptions,
    ) -> Self {
        let rotation = attitude.to_rotation_matrix();
        let increment = 2.0 * PI / CLOUD_BINS as f64;
        let mut ranges = vec![f32::INFINITY; CLOUD_BINS];
        let mut summary = CloudSummary::default();
        for [x, y, z] in points {
            summary.points += 1;
            if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                summary.not_finite += 1;
                continue;
            }
            let world = rotation * Vector3::new(x as f64, y as f64, z as f64);
            if world.z < options.band.0 || world.z > options.band.1 {
                summary.outside_band += 1;
                continue;
            }
            let range = world.x.hypot(world.y);
            if range < options.range_min || range > options.range_max {
                summary.out_of_range += 1;
                continue;
            }
            summary.used += 1;
            let bin = &mut ranges[bin_of(world.y.atan2(world.x), increment)];
            *bin = bin.min(range as f32);
        }
        if options.field_of_view < 2.0 * PI {
            // The body's x axis, seen from above: the middle of the field of view.
            let forward = rotation * Vector3::x();
            let heading = forward.y.atan2(forward.x);
            let half = 0.5 * options.field_of_view.max(0.0);
            for (i, range) in ranges.iter_mut().enumerate() {
                let bearing = -PI + (i as f64 + 0.5) * increment;
                let off = (bearing - heading + PI).rem_euclid(2.0 * PI) - PI;
                if off.abs() > half {
                    *range = f32::NAN;
                }
            }
        }
        Self {
            scan: Scan {
                angle_min: -PI + 0.5 * increment,
                angle_increment: increment,
                range_min: options.range_min,
                range_max: options.range_max,
                ranges,
            },
            summary,
        }
    }
}

/// The bin of bearing `bearing` (radians in [−π, π]) for bins of `increment` from −π.
fn bin_of(bearing: f64, increment: f64) -> usize {
    (((bearing + PI) / increment) as usize).min(CLOUD_BINS - 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::occupancy::{Beam, Occupancy, OccupancyOptions, ScanFrame, UnknownSpace};

    fn options() -> CloudOptions {
        CloudOptions {
            band: (-0.21, 0.21),
            range_min: 0.1,
            range_max: 10.0,
            field_of_view: 2.0 * PI,
        }
    }

    /// A vertical wall `distance` ahead (x = distance), sampled every 2 cm in y and z.
    fn wall(distance: f32) -> Vec<[f32; 3]> {
        let mut points = Vec::new();
        for i in -100..=100 {
            for k in -25..=25 {
                points.push([distance, i as f32 * 0.02, k as f32 * 0.02]);
            }
        }
        points
    }

    fn bin_at(bearing: f64) -> usize {
        bin_of(bearing, 2.0 * PI / CLOUD_BINS as f64)
    }

    #[test]
    fn a_wall_ahead_gives_its_distance_straight_ahead_and_free_bins_behind() {
        let cloud = CloudScan::from_points(wall(1.5), &UnitQuaternion::identity(), &options());
        let scan = &cloud.scan;
        assert_eq!(scan.beam(bin_at(0.0)), Beam::Hit(1.5));
        // 30° off the axis the wall is 1.5 / cos 30° away (within the bin's half width).
        let slant = scan.beam(bin_at(PI / 6.0));
        let Beam::Hit(r) = slant else {
            panic!("{slant:?}")
        };
        assert!((r - 1.5 / (PI / 6.0).cos()).abs() < 0.02, "{r}");
        assert_eq!(scan.beam(bin_at(PI - 0.1)), Beam::NoReturn);
        let s = cloud.summary;
        assert_eq!(s.points, 201 * 51);
        // |z| ≤ 0.21 keeps 21 of the 51 rows.
        assert_eq!((s.used, s.outside_band), (201 * 21, 201 * 30));
    }

    #[test]
    fn the_band_is_world_aligned_under_a_tilt() {
        // Pitched 30° nose down: a point 1 m ahead in the body frame sits 0.5 m below the
        // robot in the world, outside the band; one 1 m ahead and 0.58 m up in the body frame
        // is level with it.
        let pitch = UnitQuaternion::from_euler_angles(0.0, PI / 6.0, 0.0);
        let low = [1.0, 0.0, 0.0];
        let level = [1.0, 0.0, (PI / 6.0).tan() as f32];
        let cloud = CloudScan::from_points([low, level], &pitch, &options());
        assert_eq!((cloud.summary.outside_band, cloud.summary.used), (1, 1));
        let Beam::Hit(r) = cloud.scan.beam(bin_at(0.0)) else {
            panic!()
        };
        assert!((r - 1.0 / (PI / 6.0).cos()).abs() < 1e-5, "{r}");
    }

    #[test]
    fn bearings_follow_the_heading() {
        // Yawed 90° left, the body's x axis points along world y.
        let yaw = UnitQuaternion::from_euler_angles(0.0, 0.0, PI / 2.0);
        let cloud = CloudScan::from_points([[2.0, 0.0, 0.0]], &yaw, &options());
        let scan = &cloud.scan;
        let hits: Vec<usize> = (0..CLOUD_BINS)
            .filter(|&i| scan.beam(i) != Beam::NoReturn)
            .collect();
        let [bin] = hits[..] else { panic!("{hits:?}") };
        assert!(matches!(scan.beam(bin), Beam::Hit(r) if (r - 2.0).abs() < 1e-9));
        let bearing = scan.angle_min + bin as f64 * scan.angle_increment;
        assert!(
            (bearing - PI / 2.0).abs() <= scan.angle_increment,
            "{bearing}"
        );
    }

    #[test]
    fn points_that_are_not_finite_or_out_of_range_are_counted_and_dropped() {
        let points = [
            [f32::NAN, 0.0, 0.0],
            [1.0, f32::INFINITY, 0.0],
            [0.05, 0.0, 0.0],
            [20.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
        ];
        let cloud = CloudScan::from_points(points, &UnitQuaternion::identity(), &options());
        let s = cloud.summary;
        assert_eq!(
            (s.points, s.not_finite, s.out_of_range, s.used),
            (5, 2, 2, 1)
        );
        assert_eq!(cloud.scan.beam(bin_at(0.0)), Beam::Hit(3.0));
    }

    #[test]
    fn bins_outside_the_field_of_view_are_unknown() {
        let camera = CloudOptions {
            field_of_view: PI / 2.0,
            ..options()
        };
        let cloud = CloudScan::from_points(wall(2.0), &UnitQuaternion::identity(), &camera);
        assert!(matches!(cloud.scan.beam(bin_at(0.3)), Beam::Hit(_)));
        assert_eq!(cloud.scan.beam(bin_at(PI / 2.0)), Beam::Invalid);
        assert_eq!(cloud.scan.beam(bin_at(-PI + 0.01)), Beam::Invalid);
        // Within the view and free.
        let open = CloudScan::from_points([], &UnitQuaternion::identity(), &camera);
        assert_eq!(open.scan.beam(bin_at(0.5)), Beam::NoReturn);
    }

    #[test]
    fn the_occupancy_of_a_cloud_matches_that_of_the_scan_of_the_same_wall() {
        // A 2-D scan of the wall at 1.5 m and the cloud of the same wall: the free-space test
        // agrees on points well clear of the bins' edges.
        let cloud = CloudScan::from_points(wall(1.5), &UnitQuaternion::identity(), &options());
        let beams = 360;
        let increment = 2.0 * PI / beams as f64;
        let ranges = (0..beams)
            .map(|i| {
                let bearing = -PI + i as f64 * increment;
                if bearing.cos() > 0.0 && (1.5 * bearing.tan()).abs() <= 2.0 {
                    (1.5 / bearing.cos()) as f32
                } else {
                    f32::INFINITY
                }
            })
            .collect();
        let scan = Scan {
            angle_min: -PI,
            angle_increment: increment,
            range_min: 0.1,
            range_max: 10.0,
            ranges,
        };
        let occupancy = OccupancyOptions {
            robot_radius: 0.1,
            robot_height: 0.1,
            unknown_space: UnknownSpace::Occupied,
            floor: None,
            ceiling: None,
        };
        let level = UnitQuaternion::identity();
        let from_cloud = Occupancy::build(
            &cloud.scan,
            &ScanFrame::WorldAligned.read_with(&level),
            0.0,
            &occupancy,
        );
        let from_scan = Occupancy::build(&scan, &level, 0.0, &occupancy);
        for (x, y) in [
            (1.2, 0.0),
            (1.3, 0.5),
            (1.45, 0.0),
            (-3.0, 1.0),
            (0.5, -1.0),
        ] {
            assert_eq!(
                from_cloud.is_free(x, y, 0.0),
                from_scan.is_free(x, y, 0.0),
                "({x}, {y})"
            );
        }
        assert!(from_cloud.is_free(1.2, 0.0, 0.0) && !from_cloud.is_free(1.45, 0.0, 0.0));
    }
}
