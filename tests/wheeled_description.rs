//! The wheeled robot's description read from URDFs nobody here wrote: Clearpath's Husky as
//! pybullet ships it (`urdf/husky.urdf`), variants of that file with joint limits, without
//! wheels or with a broken value, and the Crazyflie (no wheels at all).

use std::path::Path;

use approx::assert_relative_eq;
use cstep::estimator::Estimator;
use cstep::model::diff_drive::{Bound, DiffDrive, SKID_STEER_SEPARATION_MULTIPLIER};
use cstep::model::urdf::UrdfError;
use cstep::model::wheeled::WheeledDescription;
use cstep::model::Dynamics;
use cstep::parameters::Settings;

fn husky_text() -> String {
    std::fs::read_to_string("urdf/husky.urdf").unwrap()
}

fn husky() -> WheeledDescription {
    WheeledDescription::load(Path::new("urdf/husky.urdf")).expect("urdf/husky.urdf loads")
}

#[test]
fn the_huskys_wheels_mass_and_outline_come_from_its_urdf() {
    let d = husky();
    assert_eq!(d.name, "husky_robot");
    assert_eq!(d.root, "base_footprint");
    let joints: Vec<&str> = d.wheels.iter().map(|w| w.joint.as_str()).collect();
    assert_eq!(
        joints,
        [
            "front_left_wheel",
            "front_right_wheel",
            "rear_left_wheel",
            "rear_right_wheel"
        ]
    );
    // The wheel links' collision cylinders: radius 0.17775 m, length 0.1143 m.
    assert_eq!(d.wheel_radius, 0.17775);
    assert!(d.wheels.iter().all(|w| w.width == 0.1143));
    // The wheel joints' origins, (±0.256, ±0.2854) from base_link, 0.14493 + 0.03282 m up from
    // base_footprint: the wheels touch the ground.
    assert_relative_eq!(d.track, 2.0 * 0.2854, epsilon = 1e-12);
    assert_relative_eq!(d.wheelbase, 2.0 * 0.256, epsilon = 1e-12);
    assert_eq!(d.drive_centre, [0.0, 0.0]);
    for w in &d.wheels {
        assert_relative_eq!(w.centre.z, d.wheel_radius, epsilon = 1e-12);
    }
    // The chassis (33.455 kg) and four wheels (2.637 kg each).
    assert_relative_eq!(d.mass, 33.455 + 4.0 * 2.637, epsilon = 1e-9);
    // Chassis izz and its centre of mass 8.7 cm behind the centre, plus each wheel's izz and
    // its mass at (±0.256, ±0.2854).
    let chassis = 2.0296 + 33.455 * (0.08748f64.powi(2) + 0.00085f64.powi(2));
    let wheels = 4.0 * (0.04411 + 2.637 * (0.256f64.powi(2) + 0.2854f64.powi(2)));
    assert_relative_eq!(d.yaw_inertia, chassis + wheels, epsilon = 1e-9);
    // The chassis box (1.0074 m long) and the wheels, whose outer faces stand 0.2854 + 0.1143/2
    // from the centre line, wider than the box's 0.5709/2.
    assert_relative_eq!(d.outline.x[1], 1.0074 / 2.0, epsilon = 1e-9);
    assert_relative_eq!(d.outline.x[0], -1.0074 / 2.0, epsilon = 1e-9);
    assert_relative_eq!(d.outline.y[1], 0.2854 + 0.1143 / 2.0, epsilon = 1e-6);
    assert_relative_eq!(d.outline.z[0], 0.0, epsilon = 1e-6);
    // No <limit> on the continuous wheel joints: the bounds come from the parameters.
    assert_eq!(d.max_rim_speed(), None);
    assert_eq!(d.max_rim_acceleration(), None);
}

#[test]
fn the_huskys_footprint_is_two_disks_that_cover_it() {
    let model = DiffDrive::new(&husky(), 1.0, 3.0, None);
    let footprint = model.footprint();
    let (half_length, half_width) = (1.0074 / 2.0, 0.2854 + 0.1143 / 2.0);
    assert_eq!(footprint.centres().len(), 2);
    assert_relative_eq!(
        footprint.radius(),
        (half_length / 2.0f64).hypot(half_width),
        epsilon = 1e-6
    );
    assert_relative_eq!(model.collision_radius(), 0.4252, epsilon = 1e-4);
    // Far narrower than the one disk around the whole robot.
    assert!(model.collision_radius() < 0.75 * half_length.hypot(half_width));
    assert_eq!(model.max_speed(), Bound::Parameter(1.0));
    assert_eq!(model.max_acceleration(), Bound::Parameter(3.0));
    assert_relative_eq!(model.collision_height(), 0.40366, epsilon = 1e-6);
}

#[test]
fn a_skid_steer_turns_on_a_wider_track_than_a_two_wheeled_drive() {
    // The Husky (two wheels a side) turns on Clearpath's calibrated 1.875 × its track unless
    // told otherwise; welding its rear wheels makes it a two-wheeled drive, which turns on its
    // geometric track.
    let track = 2.0 * 0.2854;
    let skid = DiffDrive::new(&husky(), 1.0, 3.0, None);
    assert_eq!(
        skid.separation_multiplier(),
        SKID_STEER_SEPARATION_MULTIPLIER
    );
    assert_relative_eq!(skid.effective_track(), 1.875 * track, epsilon = 1e-12);
    let calibrated = DiffDrive::new(&husky(), 1.0, 3.0, Some(1.5));
    assert_relative_eq!(calibrated.effective_track(), 1.5 * track, epsilon = 1e-12);
    let text = ["rear_left_wheel", "rear_right_wheel"]
        .iter()
        .fold(husky_text(), |t, j| {
            t.replace(
                &format!(r#"<joint name="{j}" type="continuous">"#),
                &format!(r#"<joint name="{j}" type="fixed">"#),
            )
        });
    let two = WheeledDescription::from_str(&text, "husky, rear wheels welded").unwrap();
    assert_eq!(two.wheels.len(), 2);
    let pair = DiffDrive::new(&two, 1.0, 3.0, None);
    assert_eq!(pair.separation_multiplier(), 1.0);
    assert_relative_eq!(pair.effective_track(), two.track, epsilon = 1e-12);
}

#[test]
fn joint_limits_in_the_urdf_set_the_bounds() {
    // The Husky with <limit effort="10" velocity="5"/> on its four wheel joints.
    let text = husky_text().replace(
        r#"<axis rpy="0 0 0" xyz="0 1 0"/>"#,
        r#"<axis rpy="0 0 0" xyz="0 1 0"/><limit effort="10" velocity="5"/>"#,
    );
    let d = WheeledDescription::from_str(&text, "husky with limits").unwrap();
    assert_relative_eq!(d.max_rim_speed().unwrap(), 5.0 * 0.17775, epsilon = 1e-12);
    // Four wheels each pushing with 10 N·m / r: straight against the mass, turning against the
    // yaw inertia at half the track; the smaller one binds.
    let force = 4.0 * 10.0 / 0.17775;
    let straight = force / d.mass;
    let turning = force * 0.2854f64.powi(2) / d.yaw_inertia;
    assert!(turning < straight);
    assert_relative_eq!(d.max_rim_acceleration().unwrap(), turning, epsilon = 1e-12);
    let model = DiffDrive::new(&d, 1.0, 3.0, None);
    assert_eq!(model.max_speed(), Bound::Urdf(5.0 * 0.17775));
    assert_eq!(model.max_acceleration(), Bound::Urdf(turning));
}

#[test]
fn a_urdf_without_wheels_is_refused_naming_what_was_looked_for() {
    let looked_for = "looked for continuous or revolute joints turning about the robot's \
                      lateral (y) axis whose child link has a <collision> <cylinder> along that \
                      axis, at least one on the left (y > 0) and one on the right (y < 0)";
    let cases = [
        (
            std::fs::read_to_string("urdf/cf2x.urdf").unwrap(),
            "found 0 continuous or revolute joint(s), 0 such wheel(s) on the left and 0 on the right",
        ),
        (
            // The right wheels welded on: two wheels, both on the left.
            husky_text()
                .replace(
                    r#"<joint name="front_right_wheel" type="continuous">"#,
                    r#"<joint name="front_right_wheel" type="fixed">"#,
                )
                .replace(
                    r#"<joint name="rear_right_wheel" type="continuous">"#,
                    r#"<joint name="rear_right_wheel" type="fixed">"#,
                ),
            "found 2 continuous or revolute joint(s), 2 such wheel(s) on the left and 0 on the right",
        ),
        (
            // Wheels turning about the vertical axis (casters): no drive.
            husky_text().replace(
                r#"<axis rpy="0 0 0" xyz="0 1 0"/>"#,
                r#"<axis rpy="0 0 0" xyz="0 0 1"/>"#,
            ),
            "found 4 continuous or revolute joint(s), 0 such wheel(s) on the left and 0 on the right",
        ),
    ];
    for (text, found) in cases {
        let err = WheeledDescription::from_str(&text, "robot.urdf").unwrap_err();
        assert!(matches!(err, UrdfError::NoWheels { .. }), "{err}");
        let message = err.to_string();
        assert!(
            message.starts_with("robot.urdf: no wheels found: "),
            "{message}"
        );
        assert!(message.contains(looked_for), "{message}");
        assert!(message.ends_with(found), "{message}");
    }
}

#[test]
fn a_bad_value_is_named_with_its_link_and_attribute() {
    let text = husky_text().replacen(
        r#"<cylinder length="0.1143" radius="0.17775"/>"#,
        r#"<cylinder length="0.1143" radius="big"/>"#,
        1,
    );
    let err = WheeledDescription::from_str(&text, "robot.urdf").unwrap_err();
    assert_eq!(
        err.to_string(),
        "robot.urdf: link 'front_left_wheel_link' <collision> #1 <cylinder> 'radius' must be \
         a finite number, got \"big\""
    );
    let text = husky_text().replace(r#"<mass value="33.455"/>"#, r#"<mass value="-33.455"/>"#);
    let err = WheeledDescription::from_str(&text, "robot.urdf").unwrap_err();
    assert_eq!(
        err.to_string(),
        "robot.urdf: link 'base_link' <inertial> <mass> must be a non-negative number, got \
         \"-33.455\""
    );
}

#[test]
fn model_diff_drive_selects_the_wheeled_model_from_the_configured_urdf() {
    for description in ["urdf/husky.urdf", "builtin:husky.urdf"] {
        let overrides = [
            "model:=diff_drive".to_string(),
            format!("robot_description:={description}"),
        ];
        let settings = Settings::load(None, "cstep_node", &overrides).unwrap();
        let estimator = Estimator::from_settings(&settings).unwrap();
        assert_eq!(estimator.model().name(), "diff_drive");
        assert_relative_eq!(
            estimator.settings().occupancy.robot_radius,
            0.4252,
            epsilon = 1e-4
        );
    }
    // The Crazyflie has no wheels; the Husky has no rotors.
    let settings = Settings::load(None, "cstep_node", &["model:=diff_drive".into()]).unwrap();
    let err = Estimator::from_settings(&settings).unwrap_err().to_string();
    assert!(
        err.starts_with("built-in cf2x.urdf: no wheels found"),
        "{err}"
    );
    let settings = Settings::load(
        None,
        "cstep_node",
        &["robot_description:=builtin:husky.urdf".into()],
    )
    .unwrap();
    let err = Estimator::from_settings(&settings).unwrap_err().to_string();
    assert_eq!(err, "built-in husky.urdf: <properties> element is missing");
    // A ground robot's reachable set is an area.
    let err = Settings::load(
        None,
        "cstep_node",
        &["model:=diff_drive".into(), "volume_dims:=3".into()],
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("'volume_dims' must be 2 with 'model' diff_drive"),
        "{err}"
    );
}
