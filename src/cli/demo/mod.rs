//! `cstep demo`: the node and a simulated robot — the Crazyflie flying the paper's arena, or
//! the Husky driving a hall past pallets — over real DDS on localhost, with a live table, a
//! summary and an SVG plot.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use nalgebra::UnitQuaternion;
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{MessageTypeName, Name, NodeName, NodeOptions, QosProfile};

use cstep::demo::aisle::Aisle;
use cstep::demo::arena::{Arena, Flight, PAPER_WORLD};
use cstep::demo::scene::{Lidar, Scene};
use cstep::parameters::BUILTIN_HUSKY_PATH;
use cstep::ros::convert::scan_to_laser_scan;
use cstep::ros::messages::{
    EmpoweredReward, Empowerment, Header, LaserScan, Odometry, PoseStamped, RosMessage, Time,
};
use cstep::ros::rcl::args::RosArgs;
use cstep::ros::rcl::context::{context_from_env, ContextError};

use super::node::stop_on_ctrl_c;
use super::CliError;
use plot::{flight_svg, FlightSample, Map};

mod plot;

/// Arguments of `cstep demo`.
#[derive(Debug, clap::Args)]
pub struct DemoArgs {
    /// The robot: the Crazyflie in the paper's arena, or Clearpath's Husky (`model:
    /// diff_drive`, its URDF as shipped) in a hall with pallets.
    #[arg(long, value_enum, default_value_t = Robot::Crazyflie)]
    robot: Robot,
    /// Seconds to run [default: the scripted route and a second at its end: 8 for the
    /// Crazyflie, 10 for the Husky].
    #[arg(long)]
    duration: Option<f64>,
    /// Where to write the SVG plot of empowerment along the flight.
    #[arg(long, default_value = "out/demo.svg")]
    plot: PathBuf,
}

/// `cstep demo`'s own failures: its arguments, its simulated drone, its plot.
#[derive(Debug, thiserror::Error)]
pub enum DemoError {
    /// `--duration` is not a positive number of seconds.
    #[error("--duration must be a positive number of seconds, got {0}")]
    Duration(f64),
    /// The drone's DDS context could not be set up from the environment.
    #[error(transparent)]
    Context(#[from] ContextError),
    /// ros2-client refuses one of the drone's fixed node or topic names.
    #[error("{0}")]
    Name(#[source] ros2_client::names::NameError),
    /// ros2-client could not create the drone's node.
    #[error("cannot create the demo drone node: {0}")]
    DroneNode(#[source] ros2_client::NodeCreateError),
    /// The DDS topic could not be created.
    #[error("topic {name}: {reason}")]
    Topic {
        /// The topic.
        name: String,
        /// ros2-client's reason.
        #[source]
        reason: ros2_client::CreateError,
    },
    /// A publisher, subscription or the spinner of the drone could not be created.
    #[error("demo drone: {0}")]
    Drone(#[source] ros2_client::CreateError),
    /// The node's topics were not discovered in time.
    #[error("the node did not appear on DDS within 20 s")]
    NodeNotFound,
    /// The node's thread panicked.
    #[error("the node thread failed")]
    NodeThread,
    /// The plot's directory could not be created.
    #[error("{}: {source}", dir.display())]
    PlotDirectory {
        /// The directory.
        dir: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The plot could not be written.
    #[error("{}: cannot write the plot: {source}", plot.display())]
    WritePlot {
        /// The plot's file.
        plot: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The flight ended without one score from the node.
    #[error("no scan was scored: the node did not answer")]
    NothingScored,
}

/// Scans per second the simulated LiDAR publishes.
const SCAN_RATE_HZ: f64 = 10.0;

/// The robots `cstep demo` can run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Robot {
    /// The Crazyflie (the built-in URDF), flying.
    Crazyflie,
    /// Clearpath's Husky (the built-in URDF, `model: diff_drive`), driving.
    Husky,
}

/// A demo's world, route and robot.
struct Course {
    /// What the run is, for its first line.
    title: &'static str,
    /// What the plot draws.
    map: Map,
    /// What the LiDAR sees.
    scene: Scene,
    /// The scripted route.
    route: Flight,
    /// The robot's scanner.
    lidar: Lidar,
    /// Height of the robot's origin, metres.
    altitude: f64,
    /// Whether the robot turns to face where it goes (a ground robot), or stays level facing
    /// +x (the drone, whose body frame is then the world's).
    faces_travel: bool,
    /// The node's parameters for this robot (`name:=value`).
    parameters: Vec<String>,
    /// Seconds to run unless `--duration` says.
    duration: f64,
}

impl Course {
    fn of(robot: Robot) -> Self {
        match robot {
            Robot::Crazyflie => {
                let arena = Arena::paper(0.0);
                Self {
                    title: "Crazyflie in the paper's arena (block centred at y = 0)",
                    map: Map {
                        bounds: arena.bounds,
                        obstacles: vec![arena.block],
                    },
                    scene: arena.scene,
                    route: Flight::past_the_block(),
                    lidar: PAPER_WORLD.lidar,
                    altitude: arena.altitude,
                    faces_travel: false,
                    parameters: Vec::new(),
                    duration: 8.0,
                }
            }
            Robot::Husky => {
                let aisle = Aisle::hall();
                Self {
                    title: "Husky (diff_drive) in a hall, through a door between pallets",
                    map: Map {
                        bounds: aisle.bounds,
                        obstacles: aisle.pallets,
                    },
                    scene: aisle.scene,
                    route: Aisle::drive(),
                    lidar: Aisle::lidar(),
                    altitude: 0.0,
                    faces_travel: true,
                    parameters: vec![
                        "model:=diff_drive".into(),
                        format!("robot_description:={BUILTIN_HUSKY_PATH}"),
                    ],
                    duration: 10.0,
                }
            }
        }
    }
}

/// Runs `cstep demo`.
pub fn run(args: DemoArgs) -> Result<(), CliError> {
    let course = Course::of(args.robot);
    let duration = args.duration.unwrap_or(course.duration);
    if !(duration.is_finite() && duration > 0.0) {
        return Err(DemoError::Duration(duration).into());
    }
    let mut ros_args = vec!["--ros-args".to_owned()];
    for parameter in &course.parameters {
        ros_args.extend(["-p".to_owned(), parameter.clone()]);
    }
    let ros_args = RosArgs::parse(&ros_args)?;
    // Never leave the machine (no static peers, no deprecated override); a private domain
    // unless the user chose one.
    std::env::set_var("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST");
    std::env::remove_var("ROS_STATIC_PEERS");
    std::env::remove_var("ROS_LOCALHOST_ONLY");
    if std::env::var_os("ROS_DOMAIN_ID").is_none() {
        std::env::set_var("ROS_DOMAIN_ID", (1 + std::process::id() % 100).to_string());
    }
    let stop = stop_on_ctrl_c()?;
    let node_stop = stop.clone();
    let node = std::thread::spawn(move || cstep::ros::node::run(&[], &ros_args, node_stop));
    let flown = fly(&course, duration, &stop);
    stop.store(true, Ordering::SeqCst);
    let node_result = node.join().map_err(|_| DemoError::NodeThread)?;
    let samples = flown?;
    node_result?;
    summarize(&samples);
    if let Some(dir) = args.plot.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| DemoError::PlotDirectory {
            dir: dir.to_owned(),
            source,
        })?;
    }
    std::fs::write(
        &args.plot,
        flight_svg(
            &course.map,
            &samples.iter().map(|s| s.sample).collect::<Vec<_>>(),
        ),
    )
    .map_err(|source| DemoError::WritePlot {
        plot: args.plot.clone(),
        source,
    })?;
    println!("plot: {}", args.plot.display());
    if samples.is_empty() {
        return Err(DemoError::NothingScored.into());
    }
    Ok(())
}

/// A scored scan with its round-trip latency.
struct Scored {
    sample: FlightSample,
    latency: Duration,
    valid: bool,
}

/// Runs the robot along `course`'s route for `duration` seconds: publishes odometry and scans
/// at 10 Hz and collects the node's answers.
fn fly(
    course: &Course,
    duration: f64,
    stop: &std::sync::atomic::AtomicBool,
) -> Result<Vec<Scored>, DemoError> {
    let context = context_from_env(false)?;
    let mut node = context
        .new_node(
            NodeName::new("/", "cstep_demo_drone").map_err(DemoError::Name)?,
            NodeOptions::new().enable_rosout(false),
        )
        .map_err(DemoError::DroneNode)?;
    let reliable = QosProfile::publisher_default()
        .reliability_reliable(WhenFull::Wait(Duration::from_millis(10)))
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 50 });
    let topic = |name: &str, type_name: MessageTypeName| {
        node.create_topic(
            &Name::parse(name).map_err(DemoError::Name)?,
            type_name,
            &reliable,
        )
        .map_err(|reason| DemoError::Topic {
            name: name.to_owned(),
            reason,
        })
    };
    let odom_topic = topic("/odom", Odometry::type_name())?;
    let scan_topic = topic("/scan", LaserScan::type_name())?;
    let empowerment_topic = topic("/cstep/empowerment", Empowerment::type_name())?;
    let reward_topic = topic("/cstep/reward", EmpoweredReward::type_name())?;
    let goal_topic = topic("/goal_pose", PoseStamped::type_name())?;
    let fail = DemoError::Drone;
    let odom_pub = node
        .create_publisher::<Odometry>(&odom_topic, None)
        .map_err(fail)?;
    let scan_pub = node
        .create_publisher::<LaserScan>(&scan_topic, None)
        .map_err(fail)?;
    let goal_pub = node
        .create_publisher::<PoseStamped>(&goal_topic, None)
        .map_err(fail)?;
    let empowerment_sub = node
        .create_subscription::<Empowerment>(&empowerment_topic, None)
        .map_err(fail)?;
    let reward_sub = node
        .create_subscription::<EmpoweredReward>(&reward_topic, None)
        .map_err(fail)?;

    let executor = smol::LocalExecutor::new();
    executor
        .spawn(node.spinner().map_err(fail)?.spin())
        .detach();
    smol::block_on(executor.run(async {
        // Wait for discovery both ways rather than sleeping blindly.
        let discovery = Instant::now();
        while odom_pub.get_subscription_count(&node) == 0
            || scan_pub.get_subscription_count(&node) == 0
            || goal_pub.get_subscription_count(&node) == 0
            || reward_sub.get_publisher_count(&node) == 0
        {
            if stop.load(Ordering::SeqCst) || discovery.elapsed() > Duration::from_secs(20) {
                return Err(DemoError::NodeNotFound);
            }
            smol::Timer::after(Duration::from_millis(50)).await;
        }
        let flight = &course.route;
        println!(
            "cstep demo: {}, {duration:.1} s, ROS_DOMAIN_ID {} (localhost only)",
            course.title,
            std::env::var("ROS_DOMAIN_ID").unwrap_or_default()
        );
        println!(
            "{:>6} {:>6} {:>6} {:>6} {:>12} {:>8} {:>10}",
            "t (s)", "x (m)", "y (m)", "v m/s", "empowerment", "reward", "latency"
        );
        let mut sent: HashMap<(i32, u32), (f64, Instant)> = HashMap::new();
        let mut pending: HashMap<(i32, u32), Empowerment> = HashMap::new();
        let mut scored = Vec::new();
        let started = Instant::now();
        let ticks = (duration * SCAN_RATE_HZ).floor() as usize;
        // A ground robot faces where it goes, and keeps its heading when it stops.
        let mut heading = 0.0_f64;
        for k in 0..=ticks + 5 {
            if stop.load(Ordering::SeqCst) {
                break;
            }
            if k <= ticks {
                let t = k as f64 / SCAN_RATE_HZ;
                let (p, v) = flight.at(t);
                let stamp = Time {
                    sec: t.floor() as i32,
                    nanosec: ((t.fract()) * 1e9).round() as u32,
                };
                let header = Header {
                    stamp,
                    frame_id: "odom".into(),
                };
                let mut odom = Odometry {
                    header: header.clone(),
                    child_frame_id: "base_link".into(),
                    ..Default::default()
                };
                odom.pose.pose.position.x = p.x;
                odom.pose.pose.position.y = p.y;
                odom.pose.pose.position.z = course.altitude;
                if course.faces_travel && v.norm() > 0.0 {
                    heading = v.y.atan2(v.x);
                }
                let attitude = if course.faces_travel {
                    UnitQuaternion::from_euler_angles(0.0, 0.0, heading)
                } else {
                    UnitQuaternion::identity()
                };
                let q = attitude.into_inner().coords;
                (odom.pose.pose.orientation.x, odom.pose.pose.orientation.y) = (q.x, q.y);
                (odom.pose.pose.orientation.z, odom.pose.pose.orientation.w) = (q.z, q.w);
                // The twist is in the body frame.
                let body = attitude.inverse() * nalgebra::Vector3::new(v.x, v.y, 0.0);
                odom.twist.twist.linear.x = body.x;
                odom.twist.twist.linear.y = body.y;
                let mut goal = PoseStamped {
                    header: header.clone(),
                    ..Default::default()
                };
                let end = flight.position(flight.duration(), course.altitude);
                (
                    goal.pose.position.x,
                    goal.pose.position.y,
                    goal.pose.position.z,
                ) = (end.x, end.y, end.z);
                // Best effort: the goal only shapes the task reward.
                let _ = goal_pub.publish(goal);
                let scan = course.scene.scan(p, &attitude, &course.lidar);
                let scan_msg = scan_to_laser_scan(
                    &scan,
                    Header {
                        stamp,
                        frame_id: "base_link".into(),
                    },
                );
                if odom_pub.publish(odom).is_ok() && scan_pub.publish(scan_msg).is_ok() {
                    sent.insert((stamp.sec, stamp.nanosec), (t, Instant::now()));
                }
            }
            let next = started + Duration::from_secs_f64((k + 1) as f64 / SCAN_RATE_HZ);
            while Instant::now() < next {
                while let Ok(Some((e, _))) = empowerment_sub.take() {
                    pending.insert((e.header.stamp.sec, e.header.stamp.nanosec), e);
                }
                while let Ok(Some((r, _))) = reward_sub.take() {
                    let key = (r.header.stamp.sec, r.header.stamp.nanosec);
                    if let (Some(e), Some(&(t, at))) = (pending.remove(&key), sent.get(&key)) {
                        let (p, v) = flight.at(t);
                        let latency = at.elapsed();
                        println!(
                            "{t:>6.1} {:>6.2} {:>6.2} {:>6.2} {:>12.3} {:>8.3} {:>7.1} ms{}",
                            p.x,
                            p.y,
                            v.norm(),
                            e.empowerment,
                            r.reward,
                            latency.as_secs_f64() * 1e3,
                            if e.valid {
                                String::new()
                            } else {
                                format!("  ({})", e.status)
                            }
                        );
                        scored.push(Scored {
                            sample: FlightSample {
                                t,
                                x: p.x,
                                y: p.y,
                                empowerment: e.empowerment,
                                reward: r.reward,
                            },
                            latency,
                            valid: e.valid,
                        });
                    }
                }
                smol::Timer::after(Duration::from_millis(2)).await;
            }
        }
        Ok(scored)
    }))
}

fn summarize(scored: &[Scored]) {
    if scored.is_empty() {
        return;
    }
    let n = scored.len();
    let valid = scored.iter().filter(|s| s.valid).count();
    let lowest = scored
        .iter()
        .min_by(|a, b| a.sample.empowerment.total_cmp(&b.sample.empowerment))
        .expect("non-empty");
    let highest = scored
        .iter()
        .max_by(|a, b| a.sample.empowerment.total_cmp(&b.sample.empowerment))
        .expect("non-empty");
    let mean = scored.iter().map(|s| s.sample.empowerment).sum::<f64>() / n as f64;
    let mut latencies: Vec<f64> = scored
        .iter()
        .map(|s| s.latency.as_secs_f64() * 1e3)
        .collect();
    latencies.sort_by(f64::total_cmp);
    let q = |p: f64| latencies[((n - 1) as f64 * p).round() as usize];
    println!("---");
    println!("scored {n} scans ({valid} valid); empowerment mean {mean:.3} nats");
    println!(
        "lowest {:.3} at t = {:.1} s, (x, y) = ({:.2}, {:.2}); highest {:.3} at t = {:.1} s",
        lowest.sample.empowerment,
        lowest.sample.t,
        lowest.sample.x,
        lowest.sample.y,
        highest.sample.empowerment,
        highest.sample.t
    );
    println!(
        "scan → score latency over DDS: median {:.1} ms, p99 {:.1} ms",
        q(0.5),
        q(0.99)
    );
}
