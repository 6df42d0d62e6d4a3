//! `cstep_scoring`: C-STEP empowerment and the empowered reward for batches of robot states,
//! from NumPy arrays, without ROS.
//!
//! `Scorer.score_batch` admits each state with the core's input checks
//! ([`cstep_core::input`], [`cstep_core::scoring::admit`]) and scores it with
//! [`cstep_core::scoring::score`] — the step the node's `/cstep/evaluate_batch` service takes —
//! or answers it with [`cstep_core::scoring::unscorable`] and the reason, as the service does;
//! so a state gets the same numbers, bit for bit, in-process as from the node. The batch is
//! scored on rayon's pool with the GIL released. Parameters are those of the one table
//! ([`cstep_core::parameters::PARAMETERS`]): same names, defaults, ranges and errors as the
//! node's parameters file and `-p` overrides.

use std::path::{Path, PathBuf};

use cstep_core::estimator::Estimator;
use cstep_core::input::{self, ScanGeometry};
use cstep_core::model::diff_drive::default_separation_multiplier;
use cstep_core::model::urdf::{RobotDescription, UrdfError};
use cstep_core::model::wheeled::WheeledDescription;
use cstep_core::occupancy::ScanFrame;
use cstep_core::parameters::{self, is_urdf_text, ParameterSet, DEFAULT_NODE_NAME};
use cstep_core::scoring::{admit, score, unscorable, Score};
use numpy::ndarray::{Dimension, Ix1, Ix2};
use numpy::{Element, PyArray1, PyReadonlyArray, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyString};
use rayon::prelude::*;
use serde_norway::Value;

/// Where parameters given as keyword arguments say they were set, in errors.
const KEYWORDS_SOURCE: &str = "Scorer keyword arguments";

/// Scores robot states with one configuration: C-STEP empowerment and the empowered reward.
///
/// ``Scorer(config=None, urdf=None, **parameter_overrides)``: ``config`` is a parameters file
/// in the node's ``ros__parameters`` form (its ``cstep_node`` or ``/**`` section), ``urdf`` the
/// robot's URDF (a path or the XML text; the ``robot_description`` parameter), and the keyword
/// arguments set parameters by the node's names (``model="point_mass"``, ``seed=3``,
/// ``safety_coefficient=2.0``), over the file, over the built-in defaults. A bad file, name or
/// value raises ``ValueError`` naming it, as the node refuses it.
#[pyclass(module = "cstep_scoring", frozen)]
struct Scorer {
    estimator: Estimator,
    safety_coefficient: f64,
    model: &'static str,
}

#[pymethods]
impl Scorer {
    #[new]
    #[pyo3(signature = (config=None, urdf=None, **parameter_overrides))]
    fn new(
        config: Option<PathBuf>,
        urdf: Option<String>,
        parameter_overrides: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let mut set = ParameterSet::builtin();
        if let Some(path) = &config {
            set.merge_file(path, DEFAULT_NODE_NAME)
                .map_err(|e| PyValueError::new_err(e.to_string()))?;
        }
        if let Some(urdf) = urdf {
            set.insert(
                "robot_description",
                Value::String(urdf),
                "Scorer urdf argument",
                None,
            );
        }
        for (name, value) in parameter_overrides.into_iter().flatten() {
            let name: String = name.extract()?;
            let value = yaml_value(&name, &value)?;
            set.insert(&name, value, KEYWORDS_SOURCE, None);
        }
        let (settings, ..) =
            parameters::validate(set).map_err(|e| PyValueError::new_err(e.to_string()))?;
        let estimator = Estimator::from_settings(&settings)
            .map_err(|e| PyValueError::new_err(format!("robot_description: {e}")))?;
        Ok(Self {
            estimator,
            safety_coefficient: settings.safety_coefficient,
            model: settings.model.name(),
        })
    }

    /// The safety coefficient ``c`` of the empowered reward ``r_d · log(c · λ)``.
    #[getter]
    fn safety_coefficient(&self) -> f64 {
        self.safety_coefficient
    }

    /// The dynamics model that rolls out the trajectories (``quadrotor`` or ``point_mass``).
    #[getter]
    fn model(&self) -> &'static str {
        self.model
    }

    /// Scores ``N`` states, each exactly as the node's ``/cstep/evaluate_batch`` service scores
    /// it (same seed, same numbers).
    ///
    /// Each state is ``nav_msgs/Odometry``'s content and its scan a ``sensor_msgs/LaserScan``'s:
    ///
    /// - ``positions``: float64 ``(N, 3)``, m, in the odometry frame;
    /// - ``orientations``: float64 ``(N, 4)``, the attitude quaternion ``(x, y, z, w)``;
    /// - ``velocities``: float64 ``(N, 3)``, m/s, linear velocity in the *body* frame;
    /// - ``angular_velocities``: float64 ``(N, 3)``, rad/s, body rates;
    /// - ``scans``: float32 ``(N, B)``, the LiDAR ranges, m (REP 117: +inf no return, -inf too
    ///   close, NaN invalid), laid out by the keyword-only ``angle_min``, ``angle_increment``
    ///   (rad), ``range_min``, ``range_max`` (m) and ``angle_max`` (rad; default
    ///   ``angle_min + (B - 1) · angle_increment``), single precision as the message carries
    ///   them;
    /// - ``goals``: None (a task reward of 1) or float64 ``(N, 3)``, m, each state's goal;
    /// - ``in_collision``: None or bool ``(N,)``, whether the simulator saw the state in
    ///   contact: such a state scores the floor without rolling out.
    ///
    /// Returns a dict of ``(N,)`` arrays: ``empowerment`` (nats), ``reward``, ``task_reward``,
    /// ``empowerment_term`` (``ln c + empowerment``), ``reachable_volume``,
    /// ``terminal_volume``, ``free_volume`` (m² or m³), ``horizon`` (s), ``num_trajectories``,
    /// ``num_colliding`` (uint32), ``valid`` (bool) and ``status`` (str objects). A state the
    /// service would refuse (a NaN, a quaternion that is no rotation, a speed beyond bounds,
    /// ranges that do not match the angles) is answered as the service answers it: the floor,
    /// ``valid`` False, and the reason naming the field in ``status`` — never a NaN. An argument
    /// of the wrong type, dtype or shape raises ``TypeError`` or ``ValueError`` naming it.
    /// The GIL is released while the batch is scored, in parallel.
    #[pyo3(signature = (
        positions, orientations, velocities, angular_velocities, scans, goals=None,
        in_collision=None, *, angle_min, angle_increment, range_min, range_max, angle_max=None
    ))]
    #[allow(clippy::too_many_arguments)] // the service's fields, one argument each
    fn score_batch<'py>(
        &self,
        py: Python<'py>,
        positions: &Bound<'py, PyAny>,
        orientations: &Bound<'py, PyAny>,
        velocities: &Bound<'py, PyAny>,
        angular_velocities: &Bound<'py, PyAny>,
        scans: &Bound<'py, PyAny>,
        goals: Option<&Bound<'py, PyAny>>,
        in_collision: Option<&Bound<'py, PyAny>>,
        angle_min: f64,
        angle_increment: f64,
        range_min: f64,
        range_max: f64,
        angle_max: Option<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let positions = rows::<3>("positions", positions, None)?;
        let n = positions.len();
        let orientations = rows::<4>("orientations", orientations, Some(n))?;
        let velocities = rows::<3>("velocities", velocities, Some(n))?;
        let angular_velocities = rows::<3>("angular_velocities", angular_velocities, Some(n))?;
        let (ranges, beams) = ranges("scans", scans, n)?;
        let goals = goals.map(|g| rows::<3>("goals", g, Some(n))).transpose()?;
        let in_collision = in_collision
            .map(|c| flags("in_collision", c, n))
            .transpose()?
            .unwrap_or_else(|| vec![false; n]);
        // As the node reads a LaserScan's angle_max written in double precision from the same.
        let angle_max =
            angle_max.unwrap_or(angle_min + beams.saturating_sub(1) as f64 * angle_increment);
        let geometry = ScanGeometry {
            angle_min: angle_min as f32,
            angle_max: angle_max as f32,
            angle_increment: angle_increment as f32,
            range_min: range_min as f32,
            range_max: range_max as f32,
        };
        let c = self.safety_coefficient;
        let answers: Vec<(Score, String)> = py.detach(|| {
            (0..n)
                .into_par_iter()
                .map(|i| {
                    let admitted = admit(
                        input::robot_state(
                            positions[i],
                            orientations[i],
                            velocities[i],
                            angular_velocities[i],
                        ),
                        input::scan(&geometry, &ranges[i * beams..(i + 1) * beams]),
                        goals
                            .as_ref()
                            .map(|g| input::goal_position(g[i]))
                            .transpose(),
                    );
                    match admitted {
                        Ok((state, scan, goal)) => {
                            let scored = score(
                                &self.estimator,
                                &state,
                                (&scan, ScanFrame::Body),
                                goal.as_ref(),
                                c,
                                in_collision[i],
                            );
                            let status = scored.estimate.status.as_str().to_owned();
                            (scored, status)
                        }
                        Err(problem) => (unscorable(&self.estimator, c), problem),
                    }
                })
                .collect()
        });
        answer_dict(py, &answers)
    }
}

/// The answers as a dict of NumPy arrays, one entry per field of the service's messages.
fn answer_dict<'py>(py: Python<'py>, answers: &[(Score, String)]) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    let column = |f: fn(&Score) -> f64| -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, answers.iter().map(|(s, _)| f(s)).collect())
    };
    dict.set_item("empowerment", column(|s| s.estimate.empowerment))?;
    dict.set_item("reward", column(|s| s.reward.reward))?;
    dict.set_item("task_reward", column(|s| s.reward.task_reward))?;
    dict.set_item("empowerment_term", column(|s| s.reward.empowerment_term))?;
    dict.set_item("reachable_volume", column(|s| s.estimate.volumes.reachable))?;
    dict.set_item("terminal_volume", column(|s| s.estimate.volumes.terminal))?;
    dict.set_item("free_volume", column(|s| s.estimate.volumes.free))?;
    dict.set_item("horizon", column(|s| s.estimate.horizon))?;
    let count = |f: fn(&Score) -> usize| -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_vec(py, answers.iter().map(|(s, _)| f(s) as u32).collect())
    };
    dict.set_item("num_trajectories", count(|s| s.estimate.num_trajectories))?;
    dict.set_item("num_colliding", count(|s| s.estimate.num_colliding))?;
    let valid: Vec<bool> = answers.iter().map(|(s, _)| s.estimate.valid()).collect();
    dict.set_item("valid", PyArray1::from_vec(py, valid))?;
    let status: Vec<Py<PyAny>> = answers
        .iter()
        .map(|(_, status)| PyString::new(py, status).into_any().unbind())
        .collect();
    dict.set_item("status", PyArray1::from_vec(py, status))?;
    Ok(dict)
}

/// What `value` is, for an error: an array's dtype and shape, or another object's type.
fn describe(value: &Bound<'_, PyAny>) -> String {
    match value.cast::<PyUntypedArray>() {
        Ok(array) => format!(
            "an array of dtype {} and shape {:?}",
            array.dtype(),
            array.shape()
        ),
        Err(_) => match value.get_type().name() {
            Ok(name) => format!("a {name}"),
            Err(_) => "an object of unknown type".to_owned(),
        },
    }
}

/// Argument `name` as a NumPy array of `T` in `D` dimensions, or a `TypeError` naming it and
/// what it should be (`wanted`, such as "a float64 array of shape (N, 3)").
fn array<'py, T: Element, D: Dimension>(
    name: &str,
    value: &Bound<'py, PyAny>,
    wanted: &str,
) -> PyResult<PyReadonlyArray<'py, T, D>> {
    value.extract().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name}: expected {wanted}, got {}",
            describe(value)
        ))
    })
}

/// A `ValueError` naming argument `name` unless its `shape` is `expected` (`None`: any length
/// along that axis); `wanted` says what it should be.
fn check_shape(
    name: &str,
    shape: &[usize],
    expected: &[Option<usize>],
    wanted: &str,
) -> PyResult<()> {
    let fits = |(&n, want): (&usize, &Option<usize>)| want.is_none_or(|w| w == n);
    if shape.len() == expected.len() && shape.iter().zip(expected).all(fits) {
        return Ok(());
    }
    Err(PyValueError::new_err(format!(
        "{name}: expected {wanted}, got shape {shape:?}"
    )))
}

/// The rows of argument `name`, a float64 array of shape `(N, COLS)` (`N` = `count` if given).
fn rows<const COLS: usize>(
    name: &str,
    value: &Bound<'_, PyAny>,
    count: Option<usize>,
) -> PyResult<Vec<[f64; COLS]>> {
    let n = count.map_or("N".to_owned(), |n| n.to_string());
    let wanted = format!("a float64 array of shape ({n}, {COLS})");
    let array = array::<f64, Ix2>(name, value, &wanted)?;
    let view = array.as_array();
    check_shape(name, view.shape(), &[count, Some(COLS)], &wanted)?;
    Ok(view
        .rows()
        .into_iter()
        .map(|row| std::array::from_fn(|j| row[j]))
        .collect())
}

/// The ranges of argument `name`, a float32 array of shape `(n, B)`, row after row, and `B`.
fn ranges(name: &str, value: &Bound<'_, PyAny>, n: usize) -> PyResult<(Vec<f32>, usize)> {
    let wanted = format!("a float32 array of shape ({n}, B)");
    let array = array::<f32, Ix2>(name, value, &wanted)?;
    let view = array.as_array();
    check_shape(name, view.shape(), &[Some(n), None], &wanted)?;
    Ok((view.iter().copied().collect(), view.ncols()))
}

/// The flags of argument `name`, a bool array of shape `(n,)`.
fn flags(name: &str, value: &Bound<'_, PyAny>, n: usize) -> PyResult<Vec<bool>> {
    let wanted = format!("a bool array of shape ({n},)");
    let array = array::<bool, Ix1>(name, value, &wanted)?;
    let view = array.as_array();
    check_shape(name, view.shape(), &[Some(n)], &wanted)?;
    Ok(view.to_vec())
}

/// A keyword argument as the YAML value a parameters file would give: bool, int, float, str or
/// None (unset); anything else is a `TypeError` naming the parameter.
fn yaml_value(name: &str, value: &Bound<'_, PyAny>) -> PyResult<Value> {
    if value.is_none() {
        Ok(Value::Null)
    } else if let Ok(flag) = value.cast::<PyBool>() {
        Ok(Value::Bool(flag.is_true()))
    } else if value.is_instance_of::<PyInt>() {
        let integer: i64 = value.extract().map_err(|_| {
            PyValueError::new_err(format!(
                "{KEYWORDS_SOURCE}: '{name}' {value} is out of range"
            ))
        })?;
        Ok(Value::Number(integer.into()))
    } else if value.is_instance_of::<PyFloat>() {
        Ok(Value::Number(value.extract::<f64>()?.into()))
    } else if let Ok(text) = value.cast::<PyString>() {
        Ok(Value::String(text.to_str()?.to_owned()))
    } else {
        Err(PyTypeError::new_err(format!(
            "{KEYWORDS_SOURCE}: '{name}' must be a bool, int, float, str or None, got {}",
            describe(value)
        )))
    }
}

/// A description read by the core from `urdf`, the XML text or a path (as the
/// `robot_description` parameter takes it); the core's refusal as a `ValueError`.
fn read_urdf<T>(
    urdf: &str,
    from_str: impl FnOnce(&str, &str) -> Result<T, UrdfError>,
    load: impl FnOnce(&Path) -> Result<T, UrdfError>,
) -> PyResult<T> {
    if is_urdf_text(urdf) {
        from_str(urdf, "robot_description (URDF text)")
    } else {
        load(Path::new(urdf))
    }
    .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// ``robot_description(urdf)``: the multirotor as the core reads it from a URDF (a path or the
/// XML text, as the ``robot_description`` parameter takes it), so the Python simulation can
/// check that it flies the robot the scorer models. A dict: ``name``, ``mass`` (kg, all links),
/// ``inertia`` (the base link's ``(ixx, iyy, izz)``), ``arm``, ``kf``, ``km``,
/// ``thrust2weight``, ``collision_radius`` (m), ``gravity`` (m/s²). A URDF the core refuses
/// raises ``ValueError`` with the core's message.
#[pyfunction]
fn robot_description<'py>(py: Python<'py>, urdf: &str) -> PyResult<Bound<'py, PyDict>> {
    let description = read_urdf(urdf, RobotDescription::from_str, RobotDescription::load)?;
    let dict = PyDict::new(py);
    dict.set_item("name", &description.name)?;
    dict.set_item("mass", description.mass)?;
    let inertia = description.inertia;
    dict.set_item("inertia", (inertia.x, inertia.y, inertia.z))?;
    dict.set_item("arm", description.arm)?;
    dict.set_item("kf", description.kf)?;
    dict.set_item("km", description.km)?;
    dict.set_item("thrust2weight", description.thrust_to_weight)?;
    dict.set_item("collision_radius", description.collision_radius)?;
    dict.set_item("gravity", description.gravity)?;
    Ok(dict)
}

/// ``wheeled_description(urdf)``: the wheeled robot as the core's ``diff_drive`` model reads it
/// from a URDF (a path or the XML text), so the Python simulation can check that it drives the
/// robot the scorer models. A dict: ``name``, ``wheel_radius`` (m, the mean), ``track`` (m, the
/// geometric one), ``separation_multiplier`` (the model's default for this drive) and
/// ``effective_track`` (m, their product), ``left_joints`` and ``right_joints`` (the wheel joints
/// by side, in joint-name order), ``mass`` (kg), ``outline_y`` and ``outline_z`` (m, the chassis's and
/// wheels' extent). A URDF the core refuses raises ``ValueError`` with the core's message.
#[pyfunction]
fn wheeled_description<'py>(py: Python<'py>, urdf: &str) -> PyResult<Bound<'py, PyDict>> {
    let description = read_urdf(urdf, WheeledDescription::from_str, WheeledDescription::load)?;
    let multiplier = default_separation_multiplier(&description);
    let side =
        |left: bool| -> Vec<&str> { description.side(left).map(|w| w.joint.as_str()).collect() };
    let dict = PyDict::new(py);
    dict.set_item("name", &description.name)?;
    dict.set_item("wheel_radius", description.wheel_radius)?;
    dict.set_item("track", description.track)?;
    dict.set_item("separation_multiplier", multiplier)?;
    dict.set_item("effective_track", description.track * multiplier)?;
    dict.set_item("left_joints", side(true))?;
    dict.set_item("right_joints", side(false))?;
    dict.set_item("mass", description.mass)?;
    dict.set_item("outline_y", description.outline.y)?;
    dict.set_item("outline_z", description.outline.z)?;
    Ok(dict)
}

/// The `cstep_scoring` module: [`Scorer`]; [`robot_description`]; [`wheeled_description`]; and
/// `PAPER_WORLD_JSON`, the paper's world as the core compiled it in (`config/paper_world.json`),
/// for the Python side to check its own copy against.
#[pymodule]
fn cstep_scoring(module: &Bound<'_, PyModule>) -> PyResult<()> {
    module.add(
        "PAPER_WORLD_JSON",
        cstep_core::demo::arena::PAPER_WORLD_JSON,
    )?;
    module.add_function(wrap_pyfunction!(robot_description, module)?)?;
    module.add_function(wrap_pyfunction!(wheeled_description, module)?)?;
    module.add_class::<Scorer>()
}
