//! The URDF loader: the Crazyflie constants, the derived rotor quantities, and one clear error
//! per kind of broken file.

use std::path::Path;

use approx::assert_relative_eq;
use cstep::model::urdf::{RobotDescription, UrdfError};

fn crazyflie() -> RobotDescription {
    RobotDescription::load(Path::new("urdf/cf2x.urdf")).expect("urdf/cf2x.urdf loads")
}

#[test]
fn crazyflie_constants() {
    let d = crazyflie();
    assert_eq!(d.name, "cf2x");
    assert_relative_eq!(d.mass, 0.027, max_relative = 1e-12);
    assert_relative_eq!(d.inertia.x, 1.4e-5, max_relative = 1e-12);
    assert_relative_eq!(d.inertia.y, 1.4e-5, max_relative = 1e-12);
    assert_relative_eq!(d.inertia.z, 2.17e-5, max_relative = 1e-12);
    assert_relative_eq!(d.arm, 0.0397);
    assert_relative_eq!(d.kf, 3.16e-10);
    assert_relative_eq!(d.km, 7.94e-12);
    assert_relative_eq!(d.thrust_to_weight, 2.25);
    assert_relative_eq!(d.max_speed, 30.0 / 3.6, max_relative = 1e-12);
    assert_relative_eq!(d.drag_coefficients.x, 9.1785e-7);
    assert_relative_eq!(d.drag_coefficients.y, 9.1785e-7);
    assert_relative_eq!(d.drag_coefficients.z, 1.0311e-6);
    assert_relative_eq!(d.prop_radius, 0.0231348);
    assert_relative_eq!(d.ground_effect_coefficient, 11.36859);
    assert_relative_eq!(d.collision_radius, 0.06, max_relative = 1e-12);
    assert_relative_eq!(d.collision_height, 0.025, max_relative = 1e-12);
    assert_eq!(d.gravity, 9.8);
}

#[test]
fn crazyflie_derived_quantities() {
    let d = crazyflie();
    assert!((d.hover_rpm() - 14_468.0).abs() <= 1.0, "{}", d.hover_rpm());
    assert!((d.max_rpm() - 21_703.0).abs() <= 1.0, "{}", d.max_rpm());
    assert!(
        (d.max_thrust() - 0.595).abs() <= 0.001,
        "{}",
        d.max_thrust()
    );
    assert_relative_eq!(d.weight(), 0.027 * 9.8, max_relative = 1e-12);
    assert_relative_eq!(
        d.max_motor_thrust() * 4.0,
        d.max_thrust(),
        max_relative = 1e-12
    );
    // Four rotors at max rpm give the max thrust.
    assert_relative_eq!(
        4.0 * d.kf * d.max_rpm().powi(2),
        d.max_thrust(),
        max_relative = 1e-12
    );
    // Two rotors at full thrust, arm/√2 from the roll axis: 2 · 0.1488 N · 0.02807 m.
    assert_relative_eq!(d.max_roll_pitch_torque(), 8.356e-3, max_relative = 1e-3);
    // Two rotors at full speed: 2 · km · max_rpm².
    assert_relative_eq!(d.max_yaw_torque(), 7.480e-3, max_relative = 1e-3);
}

#[test]
fn load_and_from_str_agree() {
    let text = std::fs::read_to_string("urdf/cf2x.urdf").unwrap();
    let from_text = RobotDescription::from_str(&text, "urdf/cf2x.urdf").unwrap();
    assert_eq!(from_text, crazyflie());
}

#[test]
fn minimal_fixture_is_valid() {
    let d = RobotDescription::load(Path::new("tests/data/minimal.urdf")).unwrap();
    assert_eq!(d.name, "minimal");
    assert_relative_eq!(d.collision_radius, 0.06, max_relative = 1e-12);
}

#[test]
fn collision_extent_covers_offset_and_tilted_shapes() {
    let xml = r#"<robot name="shapes">
      <properties arm="0.1" kf="1e-9" km="1e-11" thrust2weight="2" max_speed_kmh="36"
                  gnd_eff_coeff="0" prop_radius="0.05" drag_coeff_xy="0" drag_coeff_z="0"/>
      <link name="base">
        <inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="2"/></inertial>
        <collision><origin xyz="0.1 0 0.05"/><geometry><sphere radius="0.02"/></geometry></collision>
        <collision><geometry><box size="0.06 0.08 0.04"/></geometry></collision>
        <collision><origin rpy="1.5708 0 0"/><geometry><cylinder radius="0.03" length="0.08"/></geometry></collision>
        <collision><geometry><mesh filename="shell.stl"/></geometry></collision>
      </link>
      <link name="arm"><inertial><mass value="0.5"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
      <joint name="j" type="fixed"><parent link="base"/><child link="arm"/></joint>
    </robot>"#;
    let d = RobotDescription::from_str(xml, "<shapes>").unwrap();
    // Sphere: 0.1 off-axis + 0.02; box: half-diagonal 0.05; tilted cylinder: bounding sphere 0.05.
    assert_relative_eq!(d.collision_radius, 0.12, max_relative = 1e-12);
    // Sphere top at 0.07; tilted cylinder bottom at −0.05.
    assert_relative_eq!(d.collision_height, 0.12, max_relative = 1e-12);
    // Masses of all links add up; the inertia is the base link's.
    assert_relative_eq!(d.mass, 1.5);
    assert_relative_eq!(d.inertia.z, 2.0);
    assert_relative_eq!(d.max_speed, 10.0, max_relative = 1e-12);
}

/// Loads `tests/data/<name>` and returns the error message, asserting it names the file.
fn error_for(name: &str) -> (UrdfError, String) {
    let path = format!("tests/data/{name}");
    let err = RobotDescription::load(Path::new(&path)).expect_err(&path);
    let message = err.to_string();
    assert!(message.starts_with(&format!("{path}: ")), "{message}");
    (err, message)
}

#[test]
fn missing_file() {
    let err = RobotDescription::load(Path::new("tests/data/does_not_exist.urdf")).unwrap_err();
    assert!(matches!(err, UrdfError::Io { .. }));
    let message = err.to_string();
    assert!(
        message.starts_with("tests/data/does_not_exist.urdf: cannot read the file"),
        "{message}"
    );
}

#[test]
fn malformed_xml() {
    let (err, message) = error_for("bad_malformed.urdf");
    assert!(matches!(err, UrdfError::Xml { .. }));
    assert!(message.contains("not well-formed XML"), "{message}");
    assert!(message.contains("17:"), "names the line: {message}");
}

#[test]
fn wrong_root_element() {
    let (err, message) = error_for("bad_not_robot.urdf");
    assert!(matches!(err, UrdfError::Structure { .. }));
    assert!(
        message.contains("<model>") && message.contains("<robot>"),
        "{message}"
    );
}

#[test]
fn several_root_links() {
    let (err, message) = error_for("bad_two_roots.urdf");
    assert!(matches!(err, UrdfError::Structure { .. }));
    assert!(message.contains("root link"), "{message}");
}

#[test]
fn missing_properties_element() {
    let (err, message) = error_for("bad_no_properties.urdf");
    assert!(matches!(err, UrdfError::Missing { .. }));
    assert!(
        message.ends_with("<properties> element is missing"),
        "{message}"
    );
}

#[test]
fn missing_property() {
    let (_, message) = error_for("bad_missing_kf.urdf");
    assert_eq!(
        message,
        "tests/data/bad_missing_kf.urdf: <properties> attribute 'kf' is missing"
    );
}

#[test]
fn nan_property() {
    let (err, message) = error_for("bad_nan_drag.urdf");
    assert!(matches!(err, UrdfError::Invalid { .. }));
    assert!(message.contains("'drag_coeff_z'"), "{message}");
    assert!(
        message.contains("finite number") && message.contains("\"NaN\""),
        "{message}"
    );
}

#[test]
fn negative_property() {
    let (_, message) = error_for("bad_negative_arm.urdf");
    assert_eq!(
        message,
        "tests/data/bad_negative_arm.urdf: <properties> attribute 'arm' must be a positive number, got \"-0.0397\""
    );
}

#[test]
fn non_numeric_property() {
    let (_, message) = error_for("bad_text_km.urdf");
    assert!(
        message.contains("'km'") && message.contains("\"fast\""),
        "{message}"
    );
}

#[test]
fn thrust_too_weak_to_hover() {
    let (_, message) = error_for("bad_weak_thrust.urdf");
    assert!(
        message.contains("'thrust2weight'") && message.contains("\"0.9\""),
        "{message}"
    );
    assert!(message.contains("greater than 1"), "{message}");
}

#[test]
fn missing_inertial() {
    let (err, message) = error_for("bad_no_inertial.urdf");
    assert!(matches!(err, UrdfError::Missing { .. }));
    assert!(
        message.contains("<inertial>") && message.contains("'body'"),
        "{message}"
    );
}

#[test]
fn missing_mass() {
    let (err, message) = error_for("bad_no_mass.urdf");
    assert!(matches!(err, UrdfError::Missing { .. }));
    assert!(
        message.contains("<mass>") && message.contains("'body'"),
        "{message}"
    );
}

#[test]
fn negative_mass() {
    let (_, message) = error_for("bad_negative_mass.urdf");
    assert_eq!(
        message,
        "tests/data/bad_negative_mass.urdf: link 'body' <mass> 'value' must be a positive number, got \"-1\""
    );
}

#[test]
fn non_numeric_mass() {
    let (err, message) = error_for("bad_text_mass.urdf");
    assert!(matches!(err, UrdfError::Invalid { .. }));
    assert!(
        message.contains("<mass> 'value'") && message.contains("\"heavy\""),
        "{message}"
    );
}

#[test]
fn zero_moment_of_inertia() {
    let (_, message) = error_for("bad_zero_izz.urdf");
    assert!(
        message.contains("'izz'") && message.contains("positive"),
        "{message}"
    );
}

#[test]
fn no_collision_geometry() {
    let (err, message) = error_for("bad_no_collision.urdf");
    assert!(matches!(err, UrdfError::NoCollision { .. }));
    assert!(
        message.contains("<collision>") && message.contains("'body'"),
        "{message}"
    );
}

#[test]
fn zero_collision_radius() {
    let (_, message) = error_for("bad_zero_radius.urdf");
    assert!(
        message.contains("<collision>") && message.contains("'radius'"),
        "{message}"
    );
    assert!(message.contains("\"0\""), "{message}");
}
