//! Every parameter cstep reads, from its one definition to the settings an evaluation and the
//! node run with.
//!
//! - [`robot`] says where `robot_description` takes the URDF from;
//! - [`table`] defines each parameter once: name, type and range, default, unit, description,
//!   and whether it may change while the node runs;
//! - [`yaml`] reads the YAML a user gave (a parameters file, a `-p` value) at a cost bounded by
//!   its size;
//! - [`overrides`] reads `--params-file` and `-p` into rcl's table of node sections and picks
//!   the sections that apply to one node, as rclcpp and rclpy do;
//! - [`config`] gathers the built-in defaults, files and overrides into a [`ParameterSet`] and
//!   checks it against the table into [`Parameters`];
//! - [`settings`] reads the checked values into the evaluation's [`Settings`] and the node's
//!   [`NodeSettings`].
//!
//! Each module uses only those listed before it.

pub mod config;
pub mod overrides;
pub mod robot;
pub mod settings;
pub mod table;
pub mod yaml;

pub use config::{ConfigError, ParameterSet, Parameters, DEFAULT_NODE_NAME};
pub use overrides::{OverridesError, ParamOverrides, ParamSource};
pub use robot::{
    is_urdf_text, RobotSource, BUILTIN_HUSKY_PATH, BUILTIN_ROBOTS, BUILTIN_URDF, BUILTIN_URDF_PATH,
};
pub use settings::{load_all, validate, ModelKind, NodeSettings, Settings};
pub use table::{find, show, Change, Kind, Parameter, Rule, Value, PARAMETERS};
