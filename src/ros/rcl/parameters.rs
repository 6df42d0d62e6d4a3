//! The node's parameters on the ROS 2 parameter services: every parameter of
//! [`crate::parameters::PARAMETERS`] declared with its value and an `rcl_interfaces`
//! `ParameterDescriptor` (description, type, range, `read_only`), so `ros2 param list`,
//! `describe`, `get` and `dump` show them all; a set is checked by the same rule the parameters
//! file is, read-only ones are refused with a reason, and live ones are handed to the node.
//!
//! ros2-client 0.12.1 cannot declare descriptors: `vendor/ros2-client` adds
//! `NodeOptions::declare_parameter_with_descriptor` (`vendor/ros2-client/CSTEP_PATCH.md`).

use ros2_client::parameters::{NumericRange, ParameterDescriptor, ParameterType};
use ros2_client::{NodeOptions, ParameterValue};
use serde_norway::Value as Yaml;

use crate::excerpt::excerpt;
use crate::parameters::Parameters;
use crate::parameters::{find, Change, Kind, Parameter, Rule, Value};

/// `options` with every parameter declared at its value in `parameters`, described from the
/// table, and checked by its rule when set; `apply` gets each accepted value of a live
/// parameter (`use_sim_time` aside: ros2-client switches its clock itself).
pub fn declare(
    options: NodeOptions,
    parameters: &Parameters,
    apply: impl Fn(&'static Parameter, &Value) + Send + Sync + 'static,
) -> NodeOptions {
    let declared = parameters.iter().fold(options, |options, (p, value)| {
        options.declare_parameter_with_descriptor(ros_value(value), descriptor(p))
    });
    // ros2-client's callbacks answer Result<(), String>: the String is the refusal reason the
    // parameter services send back to the caller.
    declared
        .parameter_validator(Box::new(|name, value| {
            checked(name, value).map(|_| ()).map_err(|e| e.to_string())
        }))
        .parameter_set_action(Box::new(move |name, value| {
            if find(name).is_some_and(|p| p.change == Change::Live) {
                if let (p, Some(value)) = checked(name, value).map_err(|e| e.to_string())? {
                    apply(p, &value);
                }
            }
            Ok(())
        }))
}

/// Why a set over the parameter services is refused; its text is the reason the caller reads.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
enum SetError {
    /// The name is not one of [`crate::parameters::PARAMETERS`].
    #[error("'{}' is not a cstep parameter", excerpt(.0))]
    Unknown(String),
    /// An array or unset value, where every cstep parameter takes one value.
    #[error("'{name}' takes a single value, got {kind:?}")]
    NotSingle {
        /// The parameter.
        name: String,
        /// The type of the value set.
        kind: ParameterType,
    },
    /// The parameter's rule refuses the value ([`Parameter::check`]'s reason).
    #[error("{0}")]
    Rule(String),
}

/// The parameter named `name` and `value` checked by its rule (`None`: an optional parameter
/// unset), or why the set is refused.
fn checked(
    name: &str,
    value: &ParameterValue,
) -> Result<(&'static Parameter, Option<Value>), SetError> {
    let p = find(name).ok_or_else(|| SetError::Unknown(name.to_owned()))?;
    let value = p.check(&yaml(name, value)?).map_err(SetError::Rule)?;
    Ok((p, value))
}

/// The descriptor `ros2 param describe` shows for `p`.
fn descriptor(p: &Parameter) -> ParameterDescriptor {
    let unit = p
        .unit
        .map_or_else(String::new, |unit| format!("; unit: {unit}"));
    ParameterDescriptor {
        name: p.name.to_owned(),
        param_type: match p.rule.kind() {
            Kind::Bool => ParameterType::Bool,
            Kind::Integer => ParameterType::Integer,
            Kind::Double => ParameterType::Double,
            Kind::String => ParameterType::String,
        },
        description: p.description.to_owned(),
        additional_constraints: format!("{}{unit}", p.rule.constraint()),
        read_only: p.change == Change::ReadOnly,
        dynamic_typing: false,
        range: match p.rule {
            Rule::Integer { min, max } => NumericRange::IntegerRange {
                from_value: min,
                to_value: max,
                step: 1,
            },
            // ROS ranges are closed: 0 is in, and the rule refuses it with its own reason.
            Rule::Positive { .. } => NumericRange::FloatingPointRange {
                from_value: 0.0,
                to_value: f64::INFINITY,
                step: 0.0,
            },
            Rule::Between { min, max } if min.is_finite() || max.is_finite() => {
                NumericRange::FloatingPointRange {
                    from_value: min,
                    to_value: max,
                    step: 0.0,
                }
            }
            _ => NumericRange::NotSpecified,
        },
    }
}

/// A checked value as ROS carries it; an unset optional double is `.nan`, as in the file.
fn ros_value(value: Option<&Value>) -> ParameterValue {
    match value {
        None => ParameterValue::Double(f64::NAN),
        Some(Value::Bool(b)) => ParameterValue::Boolean(*b),
        Some(Value::Integer(i)) => ParameterValue::Integer(*i),
        Some(Value::Double(d)) => ParameterValue::Double(*d),
        Some(Value::Text(s)) => ParameterValue::String(s.clone()),
    }
}

/// A value set over the parameter services, as a parameters file would hold it, for the rule.
fn yaml(name: &str, value: &ParameterValue) -> Result<Yaml, SetError> {
    match value {
        ParameterValue::Boolean(b) => Ok(Yaml::Bool(*b)),
        ParameterValue::Integer(i) => Ok(Yaml::Number((*i).into())),
        ParameterValue::Double(d) => Ok(Yaml::Number((*d).into())),
        ParameterValue::String(s) => Ok(Yaml::String(s.clone())),
        other => Err(SetError::NotSingle {
            name: name.to_owned(),
            kind: other.to_parameter_type(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parameters::PARAMETERS;
    use crate::parameters::{load_all, DEFAULT_NODE_NAME};

    #[test]
    fn every_parameter_is_described_from_the_table() {
        for p in PARAMETERS {
            let d = descriptor(p);
            assert_eq!(d.description, p.description);
            assert_eq!(d.read_only, p.change == Change::ReadOnly, "{}", p.name);
            assert!(d.additional_constraints.starts_with(&p.rule.constraint()));
        }
        let trajectories = descriptor(find("trajectories").unwrap());
        assert_eq!(
            trajectories.range,
            NumericRange::IntegerRange {
                from_value: 1,
                to_value: 100_000,
                step: 1
            }
        );
        let horizon = descriptor(find("horizon").unwrap());
        assert_eq!(horizon.additional_constraints, "> 0; unit: s");
    }

    #[test]
    fn values_set_over_ros_are_checked_by_the_table_rules() {
        let check = |name: &str, value: ParameterValue| {
            checked(name, &value)
                .map(|(_, value)| value)
                .map_err(|e| e.to_string())
        };
        assert_eq!(
            check("safety_coefficient", ParameterValue::Double(0.5)),
            Ok(Some(Value::Double(0.5)))
        );
        assert_eq!(
            check("safety_coefficient", ParameterValue::Double(0.0)),
            Err("'safety_coefficient' must be a positive number, got 0".into())
        );
        assert!(check("safety_coefficient", ParameterValue::Double(f64::NAN)).is_err());
        assert!(check("model", ParameterValue::String("boat".into())).is_err());
        assert_eq!(
            check("seed", ParameterValue::IntegerArray(vec![1])),
            Err("'seed' takes a single value, got IntegerArray".into())
        );
        assert_eq!(
            check("speed", ParameterValue::Double(1.0)),
            Err("'speed' is not a cstep parameter".into())
        );
    }

    #[test]
    fn declared_values_read_back_as_the_file_wrote_them() {
        let (_, _, parameters) = load_all(&[], DEFAULT_NODE_NAME, &[]).unwrap();
        for (p, value) in parameters.iter() {
            let back = yaml(p.name, &ros_value(value)).unwrap();
            assert_eq!(p.check(&back).unwrap().as_ref(), value, "{}", p.name);
        }
    }
}
