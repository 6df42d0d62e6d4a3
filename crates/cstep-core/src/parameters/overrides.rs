//! Parameter overrides from `--params-file` and `-p`, merged and matched to a node as rcl and
//! rclcpp/rclpy do (rcl_yaml_param_parser 9.2, rclcpp `parameter_map.cpp`,
//! `resolve_parameter_overrides.cpp`).
//!
//! rcl reads every parameters file and `-p` rule, in command-line order, into one table of node
//! sections keyed by the name they were written under: a file's top-level keys, nested keys
//! joined by `/` down to `ros__parameters` (`drone1: cstep_node: ros__parameters:` is
//! `drone1/cstep_node`), `-p node:name:=v` under `node`, and `-p name:=v` under `/**`. A section
//! seen again (a later file, a later `-p`) keeps its place in the table and its values are
//! replaced. A node then takes, in table order, every section whose key — with a leading `/`,
//! `/*` standing for one name token and `/**` for any number — matches its fully qualified name,
//! a later section overriding an earlier one. So `-p cstep_node:x:=1` reaches only
//! `/cstep_node` (the root namespace), and a `-p x:=1` lands in the `/**` section, which loses to
//! a `/ns/node` section that came after `/**` first appeared — rcl's order, kept on purpose so
//! that a params file means the same to cstep as to an rclcpp or rclpy node (checked against
//! rclpy in `tests/python/test_ros_args.py`). The node's `--ros-args` and `cstep eval --config`
//! read parameters files through this one table, so a file means the same to both.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde_norway::{Mapping, Value};

use super::table::show;
use super::yaml::{self, YamlError};
use crate::excerpt::excerpt;

/// Where parameter overrides come from, in command-line order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ParamSource {
    /// `--params-file FILE`.
    File(PathBuf),
    /// `-p [node:]name:=value` (the value as written: YAML).
    Assignment {
        /// The node it is for (`None`: every node, rcl's `/**`).
        node: Option<String>,
        /// The parameter, `.`-separated.
        name: String,
        /// The YAML text of the value.
        value: String,
    },
}

/// One parameter override: its value, where it was set, and the directory relative paths in it
/// are relative to (its file's).
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    /// The parameter's name, `.`-separated.
    pub name: String,
    /// Its value.
    pub value: Value,
    /// The file it was read from, or "command line".
    pub source: String,
    /// The directory of that file.
    pub base_dir: Option<PathBuf>,
}

/// rcl's table of node sections (`rcl_params_t`), in the order sections first appeared.
#[derive(Debug, Clone, Default)]
pub struct ParamOverrides {
    sections: Vec<(String, Vec<Override>)>,
    /// Each section's place in `sections`, by key: a file of many sections is read in time
    /// linear in its size, not in the square of its number of sections.
    by_key: HashMap<String, usize>,
    /// Each file read, with the section keys it holds.
    files: Vec<(PathBuf, Vec<String>)>,
}

/// Why the parameter overrides could not be read.
#[derive(Debug, thiserror::Error)]
pub enum OverridesError {
    /// A parameters file could not be read.
    #[error("{}: cannot read the file: {source}", .path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A parameters file is not laid out as rcl reads one.
    #[error("{}: {problem}", .path.display())]
    BadFile {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        problem: FileError,
    },
    /// A `-p name:=value` value is not YAML, or more than [`yaml`] reads.
    #[error("command line: cannot read the value of '{}': {reason}", excerpt(.name))]
    BadValue {
        /// The parameter.
        name: String,
        /// Why.
        reason: YamlError,
    },
}

/// What is wrong with a parameters file's layout.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// The text is not YAML, or more than [`yaml`] reads.
    #[error("{0}")]
    NotYaml(YamlError),
    /// The document is not a mapping.
    #[error("expected a mapping of node names to `ros__parameters`")]
    NotMapping,
    /// A key on the node-name levels is not a string (`key` as YAML debug-prints it).
    #[error("node name {} under '{}' is not a string", excerpt(.key), excerpt(.prefix))]
    NodeNameNotString {
        /// The key.
        key: String,
        /// The node-name levels above it.
        prefix: String,
    },
    /// `ros__parameters` at the top level, with no node name above it.
    #[error("`ros__parameters` must be under a node name")]
    ParametersWithoutNode,
    /// A node's `ros__parameters` is not a mapping (the node's key).
    #[error("`{}.ros__parameters` must be a mapping", excerpt(.0))]
    ParametersNotMapping(String),
    /// A node-name level that ends without `ros__parameters` (its key).
    #[error("node '{}' has no `ros__parameters` section", excerpt(.0))]
    NoParameters(String),
}

impl ParamOverrides {
    /// Reads `sources` in order; an unreadable or malformed file is an error naming it.
    pub fn read(sources: &[ParamSource]) -> Result<Self, OverridesError> {
        let mut table = Self::default();
        for source in sources {
            match source {
                ParamSource::File(path) => table.read_file(path)?,
                ParamSource::Assignment { node, name, value } => {
                    let parsed =
                        yaml::from_str(value).map_err(|reason| OverridesError::BadValue {
                            name: name.clone(),
                            reason,
                        })?;
                    table.set(
                        node.as_deref().unwrap_or("/**"),
                        Override {
                            name: name.replace('/', "."),
                            value: parsed,
                            source: "command line".into(),
                            base_dir: None,
                        },
                    );
                }
            }
        }
        Ok(table)
    }

    /// Adds the sections of the parameters file at `path`; an unreadable or malformed file is
    /// an error naming it.
    pub fn read_file(&mut self, path: &Path) -> Result<(), OverridesError> {
        let text = crate::input::file::read_to_string(path).map_err(|source| {
            OverridesError::Unreadable {
                path: path.to_path_buf(),
                source,
            }
        })?;
        let keys = self
            .add_file(&text, path)
            .map_err(|problem| OverridesError::BadFile {
                path: path.to_path_buf(),
                problem,
            })?;
        self.files.push((path.to_path_buf(), keys));
        Ok(())
    }

    /// Adds a parameters file's sections (`path` names it and gives relative paths their base);
    /// returns their keys.
    fn add_file(&mut self, text: &str, path: &Path) -> Result<Vec<String>, FileError> {
        let document = yaml::from_str(text).map_err(FileError::NotYaml)?;
        let mut keys = Vec::new();
        match document {
            Value::Null => {} // an empty file, as rcl accepts it
            Value::Mapping(top) => self.add_level(&top, "", path, &mut keys)?,
            _ => return Err(FileError::NotMapping),
        }
        Ok(keys)
    }

    /// Reads the node-name levels of a file: keys down to `ros__parameters`, joined by `/`;
    /// each section's key goes into `keys`.
    fn add_level(
        &mut self,
        level: &Mapping,
        prefix: &str,
        path: &Path,
        keys: &mut Vec<String>,
    ) -> Result<(), FileError> {
        for (key, value) in level {
            let key = key.as_str().ok_or_else(|| FileError::NodeNameNotString {
                key: format!("{key:?}"),
                prefix: prefix.to_owned(),
            })?;
            if key == "ros__parameters" {
                if prefix.is_empty() {
                    return Err(FileError::ParametersWithoutNode);
                }
                let Value::Mapping(parameters) = value else {
                    return Err(FileError::ParametersNotMapping(prefix.to_owned()));
                };
                keys.push(prefix.to_owned());
                let mut flat = Vec::new();
                flatten("", parameters, &mut flat);
                for (name, value) in flat {
                    self.set(
                        prefix,
                        Override {
                            name,
                            value,
                            source: path.display().to_string(),
                            base_dir: path.parent().map(Path::to_path_buf),
                        },
                    );
                }
                continue;
            }
            let name = if prefix.is_empty() {
                key.to_owned()
            } else {
                format!("{prefix}/{}", key.trim_start_matches('/'))
            };
            match value {
                Value::Mapping(inner) => self.add_level(inner, &name, path, keys)?,
                _ => return Err(FileError::NoParameters(name)),
            }
        }
        Ok(())
    }

    /// Sets one override in section `key`, which keeps its place if it exists. A later value
    /// for a name the section holds goes after the earlier one, which it overrides: the value
    /// rcl gives, without searching the section for the name.
    fn set(&mut self, key: &str, entry: Override) {
        let index = *self.by_key.entry(key.to_owned()).or_insert_with(|| {
            self.sections.push((key.to_owned(), Vec::new()));
            self.sections.len() - 1
        });
        self.sections[index].1.push(entry);
    }

    /// The overrides for the node `fqn` (its fully qualified name), in the order they apply
    /// (a later one for the same name wins).
    pub fn for_node(&self, fqn: &str) -> Vec<Override> {
        self.sections
            .iter()
            .filter(|(key, _)| section_matches(key, fqn))
            .flat_map(|(_, overrides)| overrides.iter().cloned())
            .collect()
    }

    /// A warning for each parameters file none of whose sections applies to node `fqn` (rcl
    /// ignores such a file silently; a launch file may pass one file to many nodes, so this is
    /// not an error, but a misspelt node name should not go unnoticed).
    pub fn unmatched_files(&self, fqn: &str) -> Vec<String> {
        self.files
            .iter()
            .filter(|(_, keys)| !keys.iter().any(|key| section_matches(key, fqn)))
            .map(|(path, keys)| {
                format!(
                    "{}: no section for {fqn} (its sections: {}); none of its parameters apply",
                    path.display(),
                    if keys.is_empty() {
                        "none".to_owned()
                    } else {
                        excerpt(&keys.join(", ")).into_owned()
                    }
                )
            })
            .collect()
    }
}

/// Whether section `key` applies to node `fqn`: rclcpp prefixes a `/` and reads `/*` as one
/// name token and `/**` as any number of them (`"/*" -> "(/\w+)"`, the whole name matched).
pub fn section_matches(key: &str, fqn: &str) -> bool {
    let key = if key.starts_with('/') {
        key.to_owned()
    } else {
        format!("/{key}")
    };
    let pattern: Vec<&str> = key[1..].split('/').collect();
    let name: Vec<&str> = fqn.trim_start_matches('/').split('/').collect();
    matches_tokens(&pattern, &name)
}

/// Token-wise match of a pattern (`*`: one token, `**`: any number, else literal), in time
/// proportional to the product of their lengths however many `**` the pattern has: `matched[i]`
/// says whether the pattern so far can end after the name's first `i` tokens.
fn matches_tokens(pattern: &[&str], name: &[&str]) -> bool {
    let mut matched = vec![false; name.len() + 1];
    matched[0] = true;
    for &token in pattern {
        if token == "**" {
            // Any number of tokens more: every position after a reachable one is reachable.
            let first = matched.iter().position(|&m| m).unwrap_or(matched.len());
            matched[first..].fill(true);
        } else {
            // One token more, if it matches: shift right, back to front.
            for i in (1..matched.len()).rev() {
                matched[i] = matched[i - 1] && (token == "*" || token == name[i - 1]);
            }
            matched[0] = false;
        }
    }
    matched[name.len()]
}

/// Nested parameter maps as dotted names (`limits: {speed: 2}` is `limits.speed`), as in ROS 2.
fn flatten(prefix: &str, mapping: &serde_norway::Mapping, out: &mut Vec<(String, Value)>) {
    for (key, value) in mapping {
        let key = match key {
            Value::String(s) => s.clone(),
            other => show(other),
        };
        let name = if prefix.is_empty() {
            key
        } else {
            format!("{prefix}.{key}")
        };
        match value {
            Value::Mapping(inner) => flatten(&name, inner, out),
            other => out.push((name, other.clone())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(files: &[&str], assignments: &[(Option<&str>, &str, &str)]) -> ParamOverrides {
        let mut t = ParamOverrides::default();
        for (i, text) in files.iter().enumerate() {
            t.add_file(text, Path::new(&format!("/p/f{i}.yaml")))
                .unwrap();
        }
        for (node, name, value) in assignments {
            t.set(
                node.unwrap_or("/**"),
                Override {
                    name: (*name).into(),
                    value: serde_norway::from_str(value).unwrap(),
                    source: "command line".into(),
                    base_dir: None,
                },
            );
        }
        t
    }

    fn values(t: &ParamOverrides, fqn: &str) -> Vec<(String, String)> {
        let mut merged: Vec<(String, String)> = Vec::new();
        for o in t.for_node(fqn) {
            let text = serde_norway::to_string(&o.value).unwrap().trim().to_owned();
            match merged.iter_mut().find(|(n, _)| *n == o.name) {
                Some(slot) => slot.1 = text,
                None => merged.push((o.name, text)),
            }
        }
        merged.sort();
        merged
    }

    fn pairs(list: &[(&str, &str)]) -> Vec<(String, String)> {
        list.iter()
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .collect()
    }

    #[test]
    fn keys_match_fully_qualified_names_with_rclcpp_wildcards() {
        for (key, fqn, expected) in [
            ("/**", "/cstep_node", true),
            ("/**", "/a/b/cstep_node", true),
            ("/**/cstep_node", "/cstep_node", true),
            ("/**/cstep_node", "/drone1/cstep_node", true),
            ("/**/cstep_node", "/drone1/other", false),
            ("cstep_node", "/cstep_node", true),
            ("cstep_node", "/drone1/cstep_node", false),
            ("/drone1/*", "/drone1/cstep_node", true),
            ("/drone1/*", "/drone1/a/cstep_node", false),
            ("/*/cstep_node", "/drone1/cstep_node", true),
            ("/*/cstep_node", "/cstep_node", false),
            ("drone1/cstep_node", "/drone1/cstep_node", true),
            ("/drone1/**", "/drone1/a/b", true),
            ("/drone2/cstep_node", "/drone1/cstep_node", false),
            ("/**/a/**/b/**", "/x/a/y/b", true),
            ("/**/a/**/b/**", "/x/b/y/a", false),
        ] {
            assert_eq!(section_matches(key, fqn), expected, "{key} vs {fqn}");
        }
        // A key of many `**` is matched in time proportional to its length: tried one way of
        // spreading the name's tokens over them after another, this took longer than a lifetime.
        let stars = format!("{}/other", "/**".repeat(300));
        assert!(!section_matches(&stars, "/a/b/c/d/e/f/cstep_node"));
        assert!(section_matches(&format!("{stars}/**"), "/a/other/b"));
    }

    #[test]
    fn a_file_of_many_sections_is_one_table_and_warns_in_one_short_line() {
        // Regression: sections for other nodes were looked up one by one, so a file's cost grew
        // with the square of their number (15 MiB: 470 s).
        let sections: String = (0..15_000)
            .map(|i| format!("/ns/node_{i}:\n  ros__parameters:\n    a: {i}\n"))
            .collect();
        let mut t = ParamOverrides::default();
        let path = Path::new("/p/many.yaml");
        let keys = t.add_file(&sections, path).unwrap();
        t.files.push((path.to_path_buf(), keys));
        assert_eq!(t.sections.len(), 15_000);
        assert_eq!(values(&t, "/ns/node_14999"), pairs(&[("a", "14999")]));
        let warnings = t.unmatched_files("/cstep_node");
        assert_eq!(warnings.len(), 1);
        assert!(warnings[0].len() < 300, "{}", warnings[0]);
        assert!(
            warnings[0].contains("/ns/node_0, /ns/node_1, "),
            "{}",
            warnings[0]
        );
    }

    // The expectations below are what rclpy 7.1 (Jazzy) gives a node for the same files and
    // rules (tests/python/test_ros_args.py runs such cases against rclpy itself).
    const FILE: &str = "\
/**:
  ros__parameters:
    a: 1
    b: 1
/**/cstep_node:
  ros__parameters:
    b: 2
    c: 2
drone1:
  cstep_node:
    ros__parameters:
      d: 3
/drone1/*:
  ros__parameters:
    e: 4
/drone1/cstep_node:
  ros__parameters:
    a: 5
";

    #[test]
    fn sections_apply_in_the_order_they_first_appeared() {
        let t = table(&[FILE], &[]);
        assert_eq!(
            values(&t, "/cstep_node"),
            pairs(&[("a", "1"), ("b", "2"), ("c", "2")])
        );
        assert_eq!(
            values(&t, "/drone1/cstep_node"),
            pairs(&[("a", "5"), ("b", "2"), ("c", "2"), ("d", "3"), ("e", "4")])
        );
        assert_eq!(
            values(&t, "/drone1/sub/cstep_node"),
            pairs(&[("a", "1"), ("b", "2"), ("c", "2")])
        );
    }

    #[test]
    fn command_line_rules_join_their_section_where_it_first_appeared() {
        // `-p a:=9` lands in `/**`, which came before `/drone1/cstep_node`: the file's 5 wins.
        let t = table(&[FILE], &[(None, "a", "9"), (Some("cstep_node"), "x", "1")]);
        assert_eq!(values(&t, "/drone1/cstep_node")[0], pairs(&[("a", "5")])[0]);
        assert!(!values(&t, "/drone1/cstep_node")
            .iter()
            .any(|(n, _)| n == "x"));
        // In the root namespace the node-scoped rule applies, and `a` is the command line's.
        let root = values(&t, "/cstep_node");
        assert!(root.contains(&("a".into(), "9".into())), "{root:?}");
        assert!(root.contains(&("x".into(), "1".into())), "{root:?}");
        // Without a file, -p always wins over the defaults it overrides.
        let t = table(&[], &[(None, "a", "1"), (None, "a", "2")]);
        assert_eq!(values(&t, "/any/node"), pairs(&[("a", "2")]));
    }

    #[test]
    fn a_later_file_replaces_values_in_place() {
        let first =
            "/**:\n  ros__parameters:\n    a: 1\n/cstep_node:\n  ros__parameters:\n    a: 2\n";
        let second = "/**:\n  ros__parameters:\n    a: 3\n";
        let t = table(&[first, second], &[]);
        assert_eq!(values(&t, "/cstep_node"), pairs(&[("a", "2")]));
        let t = table(&[second, first], &[]);
        assert_eq!(values(&t, "/cstep_node"), pairs(&[("a", "2")]));
    }

    #[test]
    fn nested_parameters_become_dotted_names_and_bad_layouts_are_errors() {
        let t = table(
            &["n:\n  ros__parameters:\n    limits:\n      speed: 2.0\n"],
            &[],
        );
        assert_eq!(values(&t, "/n"), pairs(&[("limits.speed", "2.0")]));
        let mut t = ParamOverrides::default();
        let path = Path::new("p.yaml");
        for (text, part) in [
            ("n: 3\n", "no `ros__parameters`"),
            ("n:\n  ros__parameters: 3\n", "must be a mapping"),
            ("- a\n", "expected a mapping"),
            ("ros__parameters:\n  a: 1\n", "under a node name"),
            ("n: [\n", "not valid YAML"),
        ] {
            let e = t.add_file(text, path).unwrap_err().to_string();
            assert!(e.contains(part), "{text}: {e}");
        }
        t.add_file("", path).unwrap();
    }
}
