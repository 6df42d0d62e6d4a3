//! One node's configuration as it is gathered and checked: a [`ParameterSet`] of raw values,
//! each remembering where it was set (the built-in defaults, then files, then `-p` overrides),
//! checked one by one against [`PARAMETERS`] into [`Parameters`]. A name the table does not
//! define is reported as unknown, so a typo never silently falls back to a default.

use std::collections::BTreeMap;
use std::path::Path;

use serde_norway::Value;

use super::overrides::{OverridesError, ParamOverrides};
use super::robot::is_urdf_text;
use super::table::{Parameter, Value as Typed, PARAMETERS};
use crate::excerpt::excerpt;

/// The node name whose parameters are read when none is given.
pub const DEFAULT_NODE_NAME: &str = "cstep_node";

/// A parameter file or value that cannot be used, with where it came from.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{source_name}: {message}")]
pub struct ConfigError {
    /// The file (or "command line") the bad value came from.
    pub source_name: String,
    /// What is wrong, naming the parameter and the value.
    pub message: String,
}

impl ConfigError {
    pub(super) fn new(source_name: &str, message: impl Into<String>) -> Self {
        Self {
            source_name: source_name.to_owned(),
            message: message.into(),
        }
    }
}

/// Parameter values by name, each remembering where it was set.
#[derive(Debug, Clone, Default)]
pub struct ParameterSet {
    values: BTreeMap<String, (Value, String)>,
}

impl ParameterSet {
    /// The built-in defaults, from [`PARAMETERS`].
    pub fn builtin() -> Self {
        let values = PARAMETERS.iter().map(|p| {
            let value = serde_norway::from_str(p.default).expect("a default reads as YAML");
            (p.name.to_owned(), (value, "built-in defaults".to_owned()))
        });
        Self {
            values: values.collect(),
        }
    }

    /// Overlays the sections of the parameters file `path` that apply to node `node_name` (a
    /// bare name is the root namespace's), matched by rcl's rules ([`super::overrides`]:
    /// `/ns/node`, `/**`, `/**/node`, nested namespace keys); a file with none for it is an
    /// error here, where one file configures one evaluation.
    pub fn merge_file(&mut self, path: &Path, node_name: &str) -> Result<(), ConfigError> {
        let source = path.display().to_string();
        let mut table = ParamOverrides::default();
        table.read_file(path).map_err(|e| {
            let problem = match e {
                OverridesError::Unreadable { source, .. } => {
                    format!("cannot read the file: {source}")
                }
                OverridesError::BadFile { problem, .. } => problem.to_string(),
                other => other.to_string(),
            };
            ConfigError::new(&source, problem)
        })?;
        let fqn = format!("/{}", node_name.trim_start_matches('/'));
        if !table.unmatched_files(&fqn).is_empty() {
            let bare = node_name.trim_start_matches('/');
            return Err(ConfigError::new(
                &source,
                format!("no parameters for node '{bare}' (expected a '{bare}:' or '/**:' section)"),
            ));
        }
        for o in table.for_node(&fqn) {
            self.insert(&o.name, o.value, &o.source, o.base_dir.as_deref());
        }
        Ok(())
    }

    /// Overlays one `name:=value` assignment from the command line (the value is read as YAML).
    pub fn assign(&mut self, assignment: &str) -> Result<(), ConfigError> {
        let source = "command line";
        let (name, value) = assignment.split_once(":=").ok_or_else(|| {
            ConfigError::new(
                source,
                format!(
                    "'{}' is not a parameter assignment of the form name:=value",
                    excerpt(assignment)
                ),
            )
        })?;
        let value = super::yaml::from_str(value).map_err(|e| {
            ConfigError::new(
                source,
                format!("cannot read the value of '{}': {e}", excerpt(name)),
            )
        })?;
        self.values
            .insert(name.trim().to_owned(), (value, source.to_owned()));
        Ok(())
    }

    /// Sets `name` to `value`, read from `source` (a file, whose directory `base_dir` relative
    /// paths are relative to, or the command line): for overrides gathered elsewhere, such as
    /// the node's `--ros-args` ([`super::overrides`]).
    pub fn insert(&mut self, name: &str, value: Value, source: &str, base_dir: Option<&Path>) {
        let value = if name == "robot_description" {
            resolve_path(value, base_dir)
        } else {
            value
        };
        self.values
            .insert(name.to_owned(), (value, source.to_owned()));
    }

    /// Checks every parameter against its definition, defaults filling what no file or
    /// override set; fails on the first bad value (naming where it was set), then on the first
    /// name the table does not define.
    pub fn check(mut self) -> Result<Parameters, ConfigError> {
        let mut checked = BTreeMap::new();
        for p in PARAMETERS {
            let (value, source) = self
                .values
                .remove(p.name)
                .unwrap_or((Value::Null, "parameters".to_owned()));
            let value = p
                .check(&value)
                .map_err(|message| ConfigError::new(&source, message))?;
            checked.insert(p.name, (value, source));
        }
        match self.values.into_iter().next() {
            None => Ok(Parameters { values: checked }),
            Some((name, (_, source))) => {
                let known = PARAMETERS.iter().map(|p| p.name);
                // A misspelling names the parameter meant; anything else lists them all.
                let hint = match crate::suggest::nearest(&name, known.clone()) {
                    Some(meant) => format!(", did you mean '{meant}'?"),
                    None => format!(" (known: {})", known.collect::<Vec<_>>().join(", ")),
                };
                Err(ConfigError::new(
                    &source,
                    format!("unknown parameter '{}'{hint}", excerpt(&name)),
                ))
            }
        }
    }
}

/// Every parameter's checked value (`None`: an optional one left unset) and where it was set.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameters {
    values: BTreeMap<&'static str, (Option<Typed>, String)>,
}

impl Parameters {
    /// The value of `name`; `None` when it is unset or not a parameter.
    pub fn get(&self, name: &str) -> Option<&Typed> {
        self.values.get(name).and_then(|(value, _)| value.as_ref())
    }

    /// Where `name` was set: a file, "command line" or "built-in defaults".
    pub(super) fn source(&self, name: &str) -> String {
        self.values
            .get(name)
            .map_or_else(String::new, |(_, source)| source.clone())
    }

    /// Every parameter's definition and value, in the table's order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static Parameter, Option<&Typed>)> {
        PARAMETERS.iter().map(|p| (p, self.get(p.name)))
    }

    pub(super) fn double(&self, name: &str) -> Option<f64> {
        match self.get(name) {
            Some(Typed::Double(v)) => Some(*v),
            None => None,
            Some(other) => unreachable!("'{name}' is a double in the table, got {other:?}"),
        }
    }

    pub(super) fn required_double(&self, name: &str) -> f64 {
        self.double(name)
            .unwrap_or_else(|| unreachable!("the table requires '{name}'"))
    }

    pub(super) fn integer(&self, name: &str) -> i64 {
        match self.get(name) {
            Some(Typed::Integer(v)) => *v,
            other => unreachable!("'{name}' is a required integer in the table, got {other:?}"),
        }
    }

    pub(super) fn text(&self, name: &str) -> &str {
        match self.get(name) {
            Some(Typed::Text(v)) => v,
            other => unreachable!("'{name}' is a required string in the table, got {other:?}"),
        }
    }

    pub(super) fn flag(&self, name: &str) -> bool {
        match self.get(name) {
            Some(Typed::Bool(v)) => *v,
            other => unreachable!("'{name}' is a required bool in the table, got {other:?}"),
        }
    }

    /// The word set for `name`, parsed by `parse`: the table's choices are exactly the words
    /// `parse` knows (`settings::tests::table_choices_are_the_names_the_code_parses`).
    pub(super) fn choice<T>(&self, name: &str, parse: impl Fn(&str) -> Option<T>) -> T {
        let word = self.text(name);
        parse(word).unwrap_or_else(|| unreachable!("'{name}': the table allows {word}"))
    }
}

fn resolve_path(value: Value, base_dir: Option<&Path>) -> Value {
    match (&value, base_dir) {
        (Value::String(s), Some(dir))
            if Path::new(s).is_relative() && !s.starts_with("builtin:") && !is_urdf_text(s) =>
        {
            Value::String(dir.join(s).display().to_string())
        }
        _ => value,
    }
}
