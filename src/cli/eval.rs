//! `cstep eval`: one evaluation from message files, for scripts and for checking the node.

use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use serde::de::DeserializeOwned;
use serde::Serialize;

use cstep::estimator::Estimator;
use cstep::excerpt::excerpt;
use cstep::occupancy::ScanFrame;
use cstep::parameters::{Settings, DEFAULT_NODE_NAME};
use cstep::ros::convert::{
    empowerment_message, goal_position, laser_scan_to_scan, odometry_to_state, InputError,
};
use cstep::ros::messages::json::{from_json, JsonError};
use cstep::ros::messages::{Empowerment, Header, LaserScan, Odometry, Point};
use cstep::scoring::{score, Score};

use super::{CliError, Format};

/// Arguments of `cstep eval`.
#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// Parameters file (ros__parameters YAML), e.g. config/cstep.yaml.
    #[arg(long)]
    config: PathBuf,
    /// nav_msgs/Odometry as JSON (ROS field names).
    #[arg(long)]
    odom: PathBuf,
    /// sensor_msgs/LaserScan as JSON (ROS field names; null for inf/NaN as in rosbridge).
    #[arg(long)]
    scan: PathBuf,
    /// Goal position X,Y[,Z] for the task reward exp(−‖p − goal‖); without it the task reward is 1.
    #[arg(long, value_name = "X,Y,Z")]
    goal: Option<String>,
    /// Seed of the control sample (overrides the `seed` parameter).
    #[arg(long)]
    seed: Option<u64>,
    /// Parameter override, `name:=value` (repeatable).
    #[arg(short = 'p', long = "param", value_name = "NAME:=VALUE")]
    params: Vec<String>,
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
}

/// What `cstep eval --format json` prints: the fields of `cstep_msgs/Empowerment` plus the reward.
#[derive(Debug, Serialize)]
struct EvalOutput {
    #[serde(flatten)]
    empowerment: Empowerment,
    reward: f64,
    task_reward: f64,
    empowerment_term: f64,
}

/// What is wrong with `cstep eval`'s input files or `--goal`: one line naming the file (or
/// `--goal`), the field and the value.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// A message file could not be read.
    #[error("{}: cannot read the file: {source}", path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A message file is not JSON, or not the message's fields (a misspelt field included).
    #[error("{}: not a valid message: {source}", path.display())]
    NotMessage {
        /// The file.
        path: PathBuf,
        /// Where and what: the field's path and what is wrong with it.
        source: JsonError,
    },
    /// A message whose field cannot be used (the node would reject it alike).
    #[error("{}: {problem}", path.display())]
    Input {
        /// The file.
        path: PathBuf,
        /// The field and what is wrong with it.
        problem: InputError,
    },
    /// `--goal` is not two or three numbers; the text given.
    #[error("--goal: expected two or three numbers X,Y[,Z], got \"{}\"", excerpt(.0))]
    GoalForm(String),
    /// `--goal` is not a position the node would accept.
    #[error("--goal: {0}")]
    Goal(InputError),
}

/// Runs `cstep eval`.
pub fn run(args: EvalArgs) -> Result<(), CliError> {
    let mut overrides = args.params.clone();
    if let Some(seed) = args.seed {
        overrides.push(format!("seed:={seed}"));
    }
    let settings = Settings::load(Some(&args.config), DEFAULT_NODE_NAME, &overrides)?;
    let odom: Odometry = read_json(&args.odom)?;
    let scan_msg: LaserScan = read_json(&args.scan)?;
    let input = |path: &Path| {
        let path = path.to_owned();
        move |problem| EvalError::Input { path, problem }
    };
    let state = odometry_to_state(&odom).map_err(input(&args.odom))?;
    let scan = laser_scan_to_scan(&scan_msg).map_err(input(&args.scan))?;
    let goal = args
        .goal
        .as_deref()
        .map(|g| parse_goal(g, state.position.z))
        .transpose()?;

    let estimator = Estimator::from_settings(&settings)?;
    let Score { estimate, reward } = score(
        &estimator,
        &state,
        (&scan, ScanFrame::Body),
        goal.as_ref(),
        settings.safety_coefficient,
        false,
    );
    let header = Header {
        stamp: scan_msg.header.stamp,
        frame_id: odom.header.frame_id.clone(),
    };
    let output = EvalOutput {
        empowerment: empowerment_message(header, &estimate, settings.safety_coefficient),
        reward: reward.reward,
        task_reward: reward.task_reward,
        empowerment_term: reward.empowerment_term,
    };
    match args.format {
        Format::Json => println!(
            "{}",
            serde_json::to_string_pretty(&output).map_err(CliError::Json)?
        ),
        Format::Text => {
            let e = &output.empowerment;
            let unit = if settings.volume_dims.count() == 2 {
                "m²"
            } else {
                "m³"
            };
            println!("empowerment      {:.4} nats ({})", e.empowerment, e.status);
            println!("reachable volume {:.4} {unit}", e.reachable_volume);
            println!("terminal volume  {:.4} {unit}", e.terminal_volume);
            println!("free volume      {:.4} {unit}", e.free_volume);
            println!(
                "trajectories     {} ({} colliding), horizon {} s",
                e.num_trajectories, e.num_colliding, e.horizon
            );
            println!(
                "reward           {:.4} = task {:.4} × log(c·λ) {:.4}, c = {}",
                output.reward, output.task_reward, output.empowerment_term, e.safety_coefficient
            );
            println!(
                "evaluation time  {:.0} µs",
                estimate.elapsed.as_secs_f64() * 1e6
            );
        }
    }
    Ok(())
}

/// The message in the JSON file at `path`: an object with the ROS field names, read strictly
/// ([`from_json`]): a misspelt field is refused with its path and the field meant, and anything
/// but an object (serde would read an array as the message's fields in order, and `[]` as the
/// default message, a robot at rest at the origin) is refused.
fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T, EvalError> {
    let text =
        cstep::input::file::read_to_string(path).map_err(|source| EvalError::Unreadable {
            path: path.to_owned(),
            source,
        })?;
    from_json(&text).map_err(|source| EvalError::NotMessage {
        path: path.to_owned(),
        source,
    })
}

/// The `--goal X,Y[,Z]` position (Z defaults to the robot's height), checked as the node checks
/// a goal.
fn parse_goal(text: &str, default_z: f64) -> Result<Vector3<f64>, EvalError> {
    let values: Result<Vec<f64>, _> = text.split(',').map(|v| v.trim().parse::<f64>()).collect();
    let goal = match values.as_deref() {
        Ok(&[x, y]) => Point { x, y, z: default_z },
        Ok(&[x, y, z]) => Point { x, y, z },
        _ => return Err(EvalError::GoalForm(text.to_owned())),
    };
    goal_position(&goal).map_err(EvalError::Goal)
}
