//! Where the robot's URDF comes from: a compiled-in robot by its `builtin:` name, a file, or
//! URDF text given in `robot_description` itself.

use std::path::PathBuf;

/// The marker path `robot_description` takes for the compiled-in Crazyflie 2.x URDF.
pub const BUILTIN_URDF_PATH: &str = "builtin:cf2x.urdf";

/// The Crazyflie 2.x URDF, compiled in for the built-in defaults.
pub const BUILTIN_URDF: &str = include_str!("../../../../urdf/cf2x.urdf");

/// The marker path `robot_description` takes for the compiled-in Clearpath Husky URDF.
pub const BUILTIN_HUSKY_PATH: &str = "builtin:husky.urdf";

/// The robots compiled in, by the `builtin:` name `robot_description` takes: the Crazyflie
/// 2.x (the default) and the Clearpath Husky as pybullet ships it (`urdf/husky.urdf`), for
/// `model: diff_drive` without a file at hand (`cstep bench`, tests).
pub const BUILTIN_ROBOTS: [(&str, &str); 2] = [
    (BUILTIN_URDF_PATH, BUILTIN_URDF),
    (
        BUILTIN_HUSKY_PATH,
        include_str!("../../../../urdf/husky.urdf"),
    ),
];

/// Where the robot's URDF comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RobotSource {
    /// A compiled-in robot, by its `builtin:` name ([`BUILTIN_ROBOTS`]).
    Builtin(&'static str),
    /// A URDF file.
    File(PathBuf),
    /// URDF text given in the parameter itself, as ROS launch files pass `robot_description`
    /// to `robot_state_publisher` (often xacro's output).
    Text(String),
}

/// Whether a `robot_description` value is URDF text rather than a path: XML starts with `<`,
/// which no path a user means does.
pub fn is_urdf_text(value: &str) -> bool {
    value.trim_start().starts_with('<')
}
