//! The `--ros-args` subset `cstep node` understands, as in rclcpp/rclpy.
//!
//! ros2-client parses no command line; this reads `--params-file FILE`, `-p name:=value`,
//! `-r from:=to` (including `__ns` and `__node`), each also in its long form.

use std::path::PathBuf;

/// What `--ros-args … [--]` asked for.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RosArgs {
    /// `--params-file` files, in order (later files override earlier ones).
    pub params_files: Vec<PathBuf>,
    /// `-p name:=value` assignments, in order.
    pub params: Vec<String>,
    /// `-r from:=to` topic and service remappings.
    pub remaps: Vec<(String, String)>,
    /// `-r __ns:=/ns`.
    pub namespace: Option<String>,
    /// `-r __node:=name`.
    pub node_name: Option<String>,
}

impl RosArgs {
    /// Parses the arguments after `--ros-args` (an optional `--` ends them; a further
    /// `--ros-args` starts another block).
    pub fn parse(args: &[String]) -> Result<Self, String> {
        let mut parsed = Self::default();
        let mut it = args.iter();
        while let Some(arg) = it.next() {
            let mut value = |flag: &str| {
                it.next()
                    .cloned()
                    .ok_or_else(|| format!("--ros-args: {flag} needs a value"))
            };
            match arg.as_str() {
                "--ros-args" | "--" => {}
                "--params-file" => parsed.params_files.push(PathBuf::from(value(arg)?)),
                "-p" | "--param" => {
                    let assignment = value(arg)?;
                    if !assignment.contains(":=") {
                        return Err(format!(
                            "--ros-args: -p expects name:=value, got \"{assignment}\""
                        ));
                    }
                    parsed.params.push(assignment);
                }
                "-r" | "--remap" => {
                    let rule = value(arg)?;
                    let (from, to) = rule.split_once(":=").ok_or_else(|| {
                        format!("--ros-args: -r expects from:=to, got \"{rule}\"")
                    })?;
                    match from {
                        "__ns" => parsed.namespace = Some(to.to_owned()),
                        "__node" | "__name" => parsed.node_name = Some(to.to_owned()),
                        _ => parsed.remaps.push((from.to_owned(), to.to_owned())),
                    }
                }
                other => return Err(format!("--ros-args: unsupported argument \"{other}\"")),
            }
        }
        Ok(parsed)
    }

    /// The name `topic` is remapped to, or `topic` itself.
    pub fn remap<'a>(&'a self, topic: &'a str) -> &'a str {
        self.remaps
            .iter()
            .rev()
            .find(|(from, _)| {
                from == topic || from.trim_start_matches('/') == topic.trim_start_matches('/')
            })
            .map_or(topic, |(_, to)| to.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(line: &str) -> Vec<String> {
        line.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn reads_the_rclcpp_forms() {
        let parsed = RosArgs::parse(&args(
            "--ros-args --params-file a.yaml -p seed:=3 --param horizon:=0.5 -r scan:=/lidar -r __ns:=/drone1 --remap __node:=monitor --",
        ))
        .unwrap();
        assert_eq!(parsed.params_files, vec![PathBuf::from("a.yaml")]);
        assert_eq!(parsed.params, vec!["seed:=3", "horizon:=0.5"]);
        assert_eq!(parsed.namespace.as_deref(), Some("/drone1"));
        assert_eq!(parsed.node_name.as_deref(), Some("monitor"));
        assert_eq!(parsed.remap("scan"), "/lidar");
        assert_eq!(parsed.remap("odom"), "odom");
    }

    #[test]
    fn bad_forms_are_clear_errors() {
        assert!(RosArgs::parse(&args("-p seed"))
            .unwrap_err()
            .contains("name:=value"));
        assert!(RosArgs::parse(&args("-r scan"))
            .unwrap_err()
            .contains("from:=to"));
        assert!(RosArgs::parse(&args("--params-file"))
            .unwrap_err()
            .contains("needs a value"));
        assert!(RosArgs::parse(&args("--enclave x"))
            .unwrap_err()
            .contains("unsupported"));
    }
}
