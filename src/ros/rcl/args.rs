//! The ROS 2 command line (`--ros-args … [--]`), read by rcl's rules (rcl 9.2, Jazzy:
//! `rcl/src/rcl/arguments.c`, `remap.c`, `node.c`), since ros2-client parses none of it.
//!
//! Every flag rcl knows is read: `-r/--remap`, `-p/--param`, `--params-file`, `--log-level`,
//! `--log-config-file`, `--log-file-name`, `-e/--enclave` and the `--enable-`/`--disable-`
//! `rosout-logs`, `stdout-logs` and `external-lib-logs` switches. As in rcl, remap and parameter
//! rules may be scoped to one node (`cstep_node:scan:=/lidar`, `cstep_node:horizon:=0.5`), a rule
//! for another node is ignored, the first matching remap rule wins, and a malformed rule or an
//! unknown flag is an error (rclcpp and rclpy refuse unknown ROS arguments too). The crate
//! `ros2args` (0.5) was considered: it neither expands names before matching remap rules nor
//! follows rcl's order of parameter overrides, nor reads nested namespace keys in parameter
//! files, so the rules are ported here and tested case by case against rcl's behaviour
//! (`tests/python/test_ros_args.py` compares with rclpy's).

use std::path::PathBuf;

use crate::excerpt::excerpt;
use crate::parameters::overrides::ParamSource;

/// The longest fully qualified topic or service name rcl accepts (rmw's
/// `RMW_TOPIC_MAX_NAME_LENGTH`: 255 characters less 8 reserved for the DDS prefixes); rcl refuses
/// a publisher, subscription or service on a longer one.
pub const MAX_NAME_LENGTH: usize = 255 - 8;

/// The longest node name rcl accepts (rmw's `RMW_NODE_NAME_MAX_NAME_LENGTH`).
pub const MAX_NODE_NAME_LENGTH: usize = 255;

/// The longest namespace rcl accepts (rmw's `RMW_NAMESPACE_MAX_LENGTH`: room left in a topic
/// name for the shortest name under it, `/x`).
pub const MAX_NAMESPACE_LENGTH: usize = MAX_NAME_LENGTH - 2;

/// What `--ros-args … [--]` asked for.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RosArgs {
    /// `--params-file FILE` and `-p [node:]name:=value`, in command-line order (the order rcl
    /// merges them in, [`crate::parameters::overrides`]).
    pub params: Vec<ParamSource>,
    /// `-r [node:]from:=to` rules, `__node` and `__ns` included, in order.
    pub remaps: Vec<RemapRule>,
    /// `--log-level LEVEL`: the default level (the last one given).
    pub log_level: Option<LogLevel>,
    /// `--log-level logger:=LEVEL`, in order (a later one for the same logger wins).
    pub logger_levels: Vec<(String, LogLevel)>,
    /// `--enable-`/`--disable-rosout-logs` (the last one given).
    pub rosout_logs: Option<bool>,
    /// `--enable-`/`--disable-stdout-logs` (the last one given).
    pub stdout_logs: Option<bool>,
    /// `--enable-`/`--disable-external-lib-logs` (the last one given).
    pub external_lib_logs: Option<bool>,
    /// `--log-config-file FILE`.
    pub log_config_file: Option<PathBuf>,
    /// `--log-file-name NAME`.
    pub log_file_name: Option<String>,
    /// `-e/--enclave ENCLAVE`.
    pub enclave: Option<String>,
}

/// A `-r` rule: `[node:]from:=to`, `[node:]__ns:=/ns` or `[node:]__node:=name`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RemapRule {
    /// The node the rule is for (`None`: every node).
    pub node: Option<String>,
    /// What it remaps.
    pub kind: Remap,
}

/// What a remap rule replaces.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Remap {
    /// `__node:=name` (or `__name:=name`): the node's name.
    NodeName(String),
    /// `__ns:=/ns`: the node's namespace.
    Namespace(String),
    /// A topic or service name (`rostopic://` or `rosservice://` restricts it to one kind).
    Name {
        /// Which kinds of names it applies to.
        applies_to: NameKinds,
        /// The name to match, as written (expanded against the node before matching).
        from: String,
        /// Its replacement, as written (expanded against the node).
        to: String,
    },
}

/// Which kinds of names a remap rule applies to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NameKinds {
    /// Topics and services (no URL scheme).
    Both,
    /// `rostopic://…`: topics only.
    Topics,
    /// `rosservice://…`: services only.
    Services,
}

/// Whether a name is a topic's or a service's (remap rules may apply to one kind only).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NameKind {
    /// A topic.
    Topic,
    /// A service.
    Service,
}

/// A logging severity, as rcutils names them (case-insensitive on the command line).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum LogLevel {
    /// `unset`: the logger follows its parent (for the default logger: `info`).
    Unset,
    /// `debug`.
    Debug,
    /// `info`.
    Info,
    /// `warn`.
    Warn,
    /// `error`.
    Error,
    /// `fatal`.
    Fatal,
}

impl LogLevel {
    /// rcutils' `rcutils_logging_severity_level_from_string`: the six names, any case.
    pub fn parse(text: &str) -> Option<Self> {
        Some(match text.to_ascii_uppercase().as_str() {
            "UNSET" => LogLevel::Unset,
            "DEBUG" => LogLevel::Debug,
            "INFO" => LogLevel::Info,
            "WARN" => LogLevel::Warn,
            "ERROR" => LogLevel::Error,
            "FATAL" => LogLevel::Fatal,
            _ => return None,
        })
    }
}

/// Why a `--ros-args` command line cannot be read: one line each, in rcl's words where rcl has
/// words for it, quoting at most an excerpt of what was given ([`excerpt`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ArgsError {
    /// An argument outside the `--ros-args` blocks (`cstep node` takes no others).
    #[error("unexpected argument \"{}\" (ROS arguments follow --ros-args)", excerpt(.0))]
    Unexpected(String),
    /// A flag at the end of the line, without its value.
    #[error("--ros-args: {flag} needs {what}")]
    MissingValue {
        /// The flag, as written (`-p`, `--params-file`, ...).
        flag: String,
        /// What it needs, e.g. "a file path".
        what: &'static str,
    },
    /// A flag rcl does not know (rclcpp and rclpy refuse it too).
    #[error("--ros-args: unknown ROS argument \"{}\"", excerpt(.0))]
    UnknownFlag(String),
    /// A malformed `-p`, `-r` or `--log-level` value.
    #[error(
        "--ros-args: couldn't parse {}: '{flag} {}': {reason}",
        reason.what(),
        excerpt(value)
    )]
    Rule {
        /// The flag, as written.
        flag: String,
        /// Its value, as written.
        value: String,
        /// What is wrong with the value.
        reason: RuleError,
    },
}

/// What is wrong with the value of a `-p`, `-r` or `--log-level` flag.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RuleError {
    /// A `-p` rule without `:=`.
    #[error("expected [node:]name:=value")]
    ParamForm,
    /// A `-p` rule with `*` in the name, which rcl does not implement either.
    #[error("wildcards in parameter names are not implemented (nor in rcl)")]
    ParamWildcard,
    /// A `-p` parameter name that is not tokens joined by `.` or `/`.
    #[error("invalid parameter name \"{}\"", excerpt(.0))]
    ParamName(String),
    /// A `-r` rule without `:=`.
    #[error("expected [node:]from:=to")]
    RemapForm,
    /// `__node:=` something that is not a node name.
    #[error("node name not remapped to invalid name \"{}\"", excerpt(.0))]
    NodeName(String),
    /// `__ns:=` something that is not a fully qualified namespace.
    #[error("namespace not remapped to a fully qualified name (found: \"{}\")", excerpt(.0))]
    Namespace(String),
    /// `*` or `**` in a remap rule, which cstep does not implement.
    #[error("wildcards ('*', '**') in a {0} are not implemented")]
    RemapWildcard(Side),
    /// `\1`-style backreferences in a remap rule, which cstep does not implement.
    #[error("backreferences are not implemented")]
    Backreference,
    /// One side of a remap rule is not a topic or service name.
    #[error("{side} \"{}\": {reason}", excerpt(name))]
    Name {
        /// Which side.
        side: Side,
        /// The name, as written.
        name: String,
        /// What is wrong with it.
        reason: InvalidName,
    },
    /// A `__node` or `__ns` replacement longer than rcl allows.
    #[error("the {what} has {length} characters, more than the {limit} rcl allows")]
    TooLong {
        /// "node name" or "namespace".
        what: &'static str,
        /// Its length.
        length: usize,
        /// rcl's limit ([`MAX_NODE_NAME_LENGTH`], [`MAX_NAMESPACE_LENGTH`]).
        limit: usize,
    },
    /// A `--log-level` level that is not one of rcutils' six.
    #[error("not one of unset, debug, info, warn, error, fatal")]
    LogLevel,
    /// `--log-level :=LEVEL`.
    #[error("the logger name is empty")]
    EmptyLoggerName,
}

impl RuleError {
    /// What kind of rule it is wrong for, as rcl's message names it.
    fn what(&self) -> &'static str {
        match self {
            RuleError::ParamForm | RuleError::ParamWildcard | RuleError::ParamName(_) => {
                "parameter override rule"
            }
            RuleError::RemapForm
            | RuleError::NodeName(_)
            | RuleError::Namespace(_)
            | RuleError::RemapWildcard(_)
            | RuleError::Backreference
            | RuleError::Name { .. }
            | RuleError::TooLong { .. } => "remap rule",
            RuleError::LogLevel | RuleError::EmptyLoggerName => "log level",
        }
    }
}

/// A side of a remap rule `from:=to`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// `from`: the name matched.
    Match,
    /// `to`: the name it becomes.
    Replacement,
}

impl std::fmt::Display for Side {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Side::Match => "match",
            Side::Replacement => "replacement",
        })
    }
}

/// Why a topic or service name, as written in a remap rule, is not one.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum InvalidName {
    /// Nothing but the `/` or `~/` prefix.
    #[error("empty name")]
    Empty,
    /// A part between `/` that is not a token (or a `{substitution}`).
    #[error("\"{}\" is not a name token (letters, digits, _)", excerpt(.0))]
    Token(String),
}

/// A topic or service name that does not resolve to a valid fully qualified ROS name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NameError {
    /// The name does not expand to a valid name ([`expand`]).
    #[error(
        "\"{}\" does not expand to a valid ROS name (got \"{}\")",
        excerpt(name),
        excerpt(expanded)
    )]
    Expansion {
        /// The name, as written.
        name: String,
        /// What it expanded to.
        expanded: String,
    },
    /// The replacement of the remap rule that matched the name does not expand to a valid
    /// name.
    #[error(
        "remap rule {}:={}: \"{}\" does not expand to a valid ROS name (got \"{}\")",
        excerpt(from),
        excerpt(to),
        excerpt(to),
        excerpt(expanded)
    )]
    Replacement {
        /// The rule's match, as written.
        from: String,
        /// The rule's replacement, as written.
        to: String,
        /// What the replacement expanded to.
        expanded: String,
    },
    /// The name resolves (remapped or not) to one longer than rcl allows.
    #[error(
        "\"{}\" has {} characters, more than the {MAX_NAME_LENGTH} rcl allows in a topic or \
         service name",
        excerpt(.0),
        .0.len()
    )]
    TooLong(String),
}

impl RosArgs {
    /// Parses a command line's ROS arguments: those after each `--ros-args`, up to `--` or the
    /// end (a further `--ros-args` starts another block). Arguments outside the blocks are not
    /// ROS arguments and are errors here, as `cstep node` takes no others.
    pub fn parse(args: &[String]) -> Result<Self, ArgsError> {
        let mut parsed = Self::default();
        let mut in_block = false;
        let mut it = args.iter();
        while let Some(arg) = it.next() {
            let arg = arg.as_str();
            if arg == "--ros-args" {
                in_block = true;
                continue;
            }
            if !in_block {
                return Err(ArgsError::Unexpected(arg.to_owned()));
            }
            if arg == "--" {
                in_block = false;
                continue;
            }
            let mut value = |what: &'static str| {
                it.next().cloned().ok_or_else(|| ArgsError::MissingValue {
                    flag: arg.to_owned(),
                    what,
                })
            };
            let bad = |value: &str, reason| ArgsError::Rule {
                flag: arg.to_owned(),
                value: value.to_owned(),
                reason,
            };
            match arg {
                "-p" | "--param" => {
                    let rule = value("a parameter rule, [node:]name:=value")?;
                    parsed
                        .params
                        .push(parse_param_rule(&rule).map_err(|why| bad(&rule, why))?);
                }
                "-r" | "--remap" => {
                    let rule = value("a remap rule, [node:]from:=to")?;
                    parsed
                        .remaps
                        .push(parse_remap_rule(&rule).map_err(|why| bad(&rule, why))?);
                }
                "--params-file" => {
                    parsed
                        .params
                        .push(ParamSource::File(PathBuf::from(value("a file path")?)));
                }
                "--log-level" => {
                    let rule = value("a level, LEVEL or logger:=LEVEL")?;
                    let level = |text: &str| {
                        LogLevel::parse(text).ok_or_else(|| bad(&rule, RuleError::LogLevel))
                    };
                    match rule.split_once(":=") {
                        Some(("", _)) => return Err(bad(&rule, RuleError::EmptyLoggerName)),
                        Some((logger, text)) => {
                            parsed.logger_levels.push((logger.to_owned(), level(text)?))
                        }
                        None => parsed.log_level = Some(level(&rule)?),
                    }
                }
                "--log-config-file" => {
                    parsed.log_config_file = Some(PathBuf::from(value("a file path")?));
                }
                "--log-file-name" => parsed.log_file_name = Some(value("a file name")?),
                "-e" | "--enclave" => parsed.enclave = Some(value("an enclave name")?),
                "--enable-rosout-logs" => parsed.rosout_logs = Some(true),
                "--disable-rosout-logs" => parsed.rosout_logs = Some(false),
                "--enable-stdout-logs" => parsed.stdout_logs = Some(true),
                "--disable-stdout-logs" => parsed.stdout_logs = Some(false),
                "--enable-external-lib-logs" => parsed.external_lib_logs = Some(true),
                "--disable-external-lib-logs" => parsed.external_lib_logs = Some(false),
                other => return Err(ArgsError::UnknownFlag(other.to_owned())),
            }
        }
        Ok(parsed)
    }

    /// The node's name: the first `__node` rule for `default` (or for every node), else
    /// `default` (rcl: the first matching rule wins).
    pub fn node_name(&self, default: &str) -> String {
        self.remaps
            .iter()
            .filter(|rule| rule.applies_to(default))
            .find_map(|rule| match &rule.kind {
                Remap::NodeName(name) => Some(name.clone()),
                _ => None,
            })
            .unwrap_or_else(|| default.to_owned())
    }

    /// The node's namespace: the first `__ns` rule for node `name` (its name after `__node`, as
    /// rcl matches it), else the root namespace.
    pub fn namespace(&self, name: &str) -> String {
        self.remaps
            .iter()
            .filter(|rule| rule.applies_to(name))
            .find_map(|rule| match &rule.kind {
                Remap::Namespace(ns) => Some(ns.clone()),
                _ => None,
            })
            .unwrap_or_else(|| "/".to_owned())
    }

    /// The fully qualified name a topic or service `name` of node `node` in `namespace` ends
    /// up with: `name` expanded ([`expand`]), then replaced by the first rule for this node and
    /// kind whose expanded `from` is the same name (its `to` expanded alike).
    pub fn resolve(
        &self,
        name: &str,
        kind: NameKind,
        node: &str,
        namespace: &str,
    ) -> Result<String, NameError> {
        let expanded = expand(name, node, namespace)?;
        for rule in self.remaps.iter().filter(|rule| rule.applies_to(node)) {
            let Remap::Name {
                applies_to,
                from,
                to,
            } = &rule.kind
            else {
                continue;
            };
            let kind_matches = matches!(
                (applies_to, kind),
                (NameKinds::Both, _)
                    | (NameKinds::Topics, NameKind::Topic)
                    | (NameKinds::Services, NameKind::Service)
            );
            if kind_matches && expand(from, node, namespace)? == expanded {
                let replaced = substitute(to, node, namespace);
                return if is_full_name(&replaced) {
                    within_length(replaced)
                } else {
                    Err(NameError::Replacement {
                        from: from.clone(),
                        to: to.clone(),
                        expanded: replaced,
                    })
                };
            }
        }
        Ok(expanded)
    }
}

impl RemapRule {
    /// Whether the rule applies to node `name`.
    fn applies_to(&self, name: &str) -> bool {
        self.node.as_deref().is_none_or(|node| node == name)
    }
}

/// rcl's lexer TOKEN: letters, digits and underscores.
fn is_token(text: &str) -> bool {
    !text.is_empty() && text.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Splits an optional `node:` prefix (a token followed by a single `:`) off a rule.
fn node_prefix(rule: &str) -> (Option<String>, &str) {
    match rule.split_once(':') {
        Some((node, rest))
            if is_token(node)
                && !rest.starts_with('=')
                && !rest.starts_with("//")
                && !node.starts_with("__") =>
        {
            (Some(node.to_owned()), rest)
        }
        _ => (None, rule),
    }
}

/// `[node:]name:=yaml value` (`arguments.c`, `_rcl_parse_param_rule`): the name is tokens
/// joined by `.` or `/`; a rule without a node is for every node (`/**`).
fn parse_param_rule(rule: &str) -> Result<ParamSource, RuleError> {
    let (node, rest) = node_prefix(rule);
    let (name, value) = rest.split_once(":=").ok_or(RuleError::ParamForm)?;
    if name.contains('*') {
        return Err(RuleError::ParamWildcard);
    }
    let valid = name
        .split(['.', '/'])
        .all(|part| is_token(part) || part.is_empty())
        && name.split('.').all(|part| !part.is_empty());
    if !valid || name.is_empty() {
        return Err(RuleError::ParamName(name.to_owned()));
    }
    Ok(ParamSource::Assignment {
        node,
        name: name.to_owned(),
        value: value.to_owned(),
    })
}

/// `[node:]__node:=name`, `[node:]__ns:=/ns` or `[node:][rostopic://|rosservice://]from:=to`
/// (`arguments.c`, `_rcl_parse_remap_begin_remap_rule`).
fn parse_remap_rule(rule: &str) -> Result<RemapRule, RuleError> {
    let (node, rest) = node_prefix(rule);
    let (from, to) = rest.split_once(":=").ok_or(RuleError::RemapForm)?;
    let kind = match from {
        "__node" | "__name" => {
            if !is_token(to) || to.starts_with(|c: char| c.is_ascii_digit()) {
                return Err(RuleError::NodeName(to.to_owned()));
            }
            if to.len() > MAX_NODE_NAME_LENGTH {
                return Err(RuleError::TooLong {
                    what: "node name",
                    length: to.len(),
                    limit: MAX_NODE_NAME_LENGTH,
                });
            }
            Remap::NodeName(to.to_owned())
        }
        "__ns" => {
            validate_namespace(to)?;
            Remap::Namespace(to.to_owned())
        }
        _ => {
            let (applies_to, from) = if let Some(name) = from.strip_prefix("rostopic://") {
                (NameKinds::Topics, name)
            } else if let Some(name) = from.strip_prefix("rosservice://") {
                (NameKinds::Services, name)
            } else {
                (NameKinds::Both, from)
            };
            for (side, name) in [(Side::Match, from), (Side::Replacement, to)] {
                if name.contains('*') {
                    return Err(RuleError::RemapWildcard(side));
                }
                if name.contains('\\') {
                    return Err(RuleError::Backreference);
                }
                check_name_syntax(name).map_err(|reason| RuleError::Name {
                    side,
                    name: name.to_owned(),
                    reason,
                })?;
            }
            Remap::Name {
                applies_to,
                from: from.to_owned(),
                to: to.to_owned(),
            }
        }
    };
    Ok(RemapRule { node, kind })
}

/// A namespace for `__ns`: fully qualified (`/`, or `/token/token…` without a trailing `/`), at
/// most [`MAX_NAMESPACE_LENGTH`] characters.
fn validate_namespace(ns: &str) -> Result<(), RuleError> {
    let valid = ns == "/"
        || (ns.starts_with('/')
            && ns[1..]
                .split('/')
                .all(|t| is_token(t) && !t.starts_with(|c: char| c.is_ascii_digit())));
    if !valid {
        return Err(RuleError::Namespace(ns.to_owned()));
    }
    if ns.len() > MAX_NAMESPACE_LENGTH {
        return Err(RuleError::TooLong {
            what: "namespace",
            length: ns.len(),
            limit: MAX_NAMESPACE_LENGTH,
        });
    }
    Ok(())
}

/// A topic or service name as written: optional `/` or `~/` (or just `~`), then tokens
/// (possibly `{substitutions}`) separated by single `/`.
fn check_name_syntax(name: &str) -> Result<(), InvalidName> {
    let body = name
        .strip_prefix("~/")
        .or_else(|| name.strip_prefix('/'))
        .unwrap_or(name);
    if name == "~" {
        return Ok(());
    }
    if body.is_empty() {
        return Err(InvalidName::Empty);
    }
    for token in body.split('/') {
        let bare = token.trim_start_matches('{').trim_end_matches('}');
        if !is_token(bare) {
            return Err(InvalidName::Token(token.to_owned()));
        }
    }
    Ok(())
}

/// rcl's `rcl_expand_topic_name`: `~` is the node's private namespace (`/ns/node`), `{node}`,
/// `{ns}` and `{namespace}` are substituted, a relative name is put in `namespace`; the result
/// is a valid fully qualified name (`rmw_validate_full_topic_name`: its characters, then its
/// length) or an error saying why.
pub fn expand(name: &str, node: &str, namespace: &str) -> Result<String, NameError> {
    let expanded = substitute(name, node, namespace);
    if is_full_name(&expanded) {
        within_length(expanded)
    } else {
        Err(NameError::Expansion {
            name: name.to_owned(),
            expanded,
        })
    }
}

/// A valid fully qualified name, unless it is longer than [`MAX_NAME_LENGTH`] (rmw checks the
/// length last, after the characters).
fn within_length(expanded: String) -> Result<String, NameError> {
    if expanded.len() > MAX_NAME_LENGTH {
        Err(NameError::TooLong(expanded))
    } else {
        Ok(expanded)
    }
}

/// `name` expanded as [`expand`] expands it, valid or not.
fn substitute(name: &str, node: &str, namespace: &str) -> String {
    let ns = namespace.trim_end_matches('/');
    let private = format!("{ns}/{node}");
    let substituted = name
        .replace("{node}", node)
        .replace("{namespace}", ns)
        .replace("{ns}", ns);
    if substituted == "~" {
        private
    } else if let Some(rest) = substituted.strip_prefix("~/") {
        format!("{private}/{rest}")
    } else if substituted.starts_with('/') {
        substituted
    } else {
        format!("{ns}/{substituted}")
    }
}

/// Whether an expanded name is a valid fully qualified name: after its leading `/`, tokens that
/// do not start with a digit, separated by single `/`.
fn is_full_name(expanded: &str) -> bool {
    expanded.len() > 1
        && !expanded.ends_with('/')
        && expanded[1..]
            .split('/')
            .all(|token| is_token(token) && !token.starts_with(|c: char| c.is_ascii_digit()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(line: &str) -> Vec<String> {
        line.split_whitespace().map(String::from).collect()
    }

    fn parse(line: &str) -> RosArgs {
        RosArgs::parse(&args(line)).unwrap()
    }

    fn error(line: &str) -> String {
        let e = RosArgs::parse(&args(line)).unwrap_err().to_string();
        assert!(!e.contains('\n'), "{e}");
        e
    }

    #[test]
    fn reads_every_flag_in_short_and_long_form() {
        let parsed = parse(
            "--ros-args --params-file a.yaml -p seed:=3 --param cstep_node:horizon:=0.5 \
             -r scan:=/lidar --remap __ns:=/drone1 -r __node:=monitor --log-level debug \
             --log-level cstep_node:=WARN --enable-rosout-logs --disable-stdout-logs \
             --disable-external-lib-logs --log-config-file log.cfg --log-file-name run \
             -e /enclave --",
        );
        assert_eq!(
            parsed.params,
            [
                ParamSource::File("a.yaml".into()),
                ParamSource::Assignment {
                    node: None,
                    name: "seed".into(),
                    value: "3".into()
                },
                ParamSource::Assignment {
                    node: Some("cstep_node".into()),
                    name: "horizon".into(),
                    value: "0.5".into()
                },
            ]
        );
        assert_eq!(parsed.node_name("cstep_node"), "monitor");
        assert_eq!(parsed.namespace("monitor"), "/drone1");
        assert_eq!(parsed.log_level, Some(LogLevel::Debug));
        assert_eq!(
            parsed.logger_levels,
            [("cstep_node".to_owned(), LogLevel::Warn)]
        );
        assert_eq!(
            (
                parsed.rosout_logs,
                parsed.stdout_logs,
                parsed.external_lib_logs
            ),
            (Some(true), Some(false), Some(false))
        );
        assert_eq!(parsed.log_config_file, Some(PathBuf::from("log.cfg")));
        assert_eq!(parsed.log_file_name.as_deref(), Some("run"));
        assert_eq!(parsed.enclave.as_deref(), Some("/enclave"));
    }

    #[test]
    fn several_blocks_and_the_last_log_level_wins() {
        let parsed = parse("--ros-args --log-level info -- --ros-args --log-level ERROR");
        assert_eq!(parsed.log_level, Some(LogLevel::Error));
        assert!(error("--ros-args -- stray").contains("unexpected argument \"stray\""));
        assert!(error("stray").contains("follow --ros-args"));
    }

    #[test]
    fn the_first_matching_node_and_namespace_rule_wins_and_scoped_rules_need_their_node() {
        let parsed = parse(
            "--ros-args -r other:__node:=x -r __node:=first -r __node:=second \
             -r other:__ns:=/o -r first:__ns:=/f -r __ns:=/g",
        );
        assert_eq!(parsed.node_name("cstep_node"), "first");
        assert_eq!(parsed.node_name("other"), "x");
        // The namespace rule is matched against the name after __node (rcl's node.c).
        assert_eq!(parsed.namespace("first"), "/f");
        assert_eq!(parsed.namespace("cstep_node"), "/g");
        assert_eq!(parse("--ros-args").namespace("cstep_node"), "/");
    }

    #[test]
    fn names_expand_as_rcl_expands_them() {
        for (name, ns, expected) in [
            ("scan", "/", "/scan"),
            ("scan", "/drone1", "/drone1/scan"),
            ("cstep/evaluate", "/drone1", "/drone1/cstep/evaluate"),
            ("/diagnostics", "/drone1", "/diagnostics"),
            ("~/debug", "/drone1", "/drone1/cstep_node/debug"),
            ("~", "/", "/cstep_node"),
            ("{node}/out", "/a/b", "/a/b/cstep_node/out"),
            ("{ns}/x", "/", "/x"),
            ("{namespace}/x", "/a", "/a/x"),
        ] {
            assert_eq!(expand(name, "cstep_node", ns).unwrap(), expected, "{name}");
        }
        for bad in ["a//b", "/", "a/", "1scan", "sc an", "/x/2y"] {
            let e = expand(bad, "cstep_node", "/").unwrap_err().to_string();
            assert!(e.contains("valid ROS name"), "{e}");
        }
    }

    #[test]
    fn remap_rules_match_expanded_names_for_their_node_and_kind() {
        let parsed = parse(
            "--ros-args -r other_node:scan:=/wrong -r cstep_node:scan:=/lidar \
             -r odom:=/first -r odom:=/second -r /cstep/evaluate:=/elsewhere \
             -r rosservice://cstep/evaluate_batch:=batch -r rostopic://cstep/reward:=~/reward",
        );
        let resolve =
            |name: &str, kind, ns: &str| parsed.resolve(name, kind, "cstep_node", ns).unwrap();
        use NameKind::{Service, Topic};
        assert_eq!(resolve("scan", Topic, "/drone1"), "/lidar");
        assert_eq!(
            parsed.resolve("scan", Topic, "other", "/").unwrap(),
            "/scan"
        );
        assert_eq!(resolve("odom", Topic, "/drone1"), "/first");
        // An absolute match names one name: /cstep/evaluate, not /drone1/cstep/evaluate.
        assert_eq!(resolve("cstep/evaluate", Service, "/"), "/elsewhere");
        assert_eq!(
            resolve("cstep/evaluate", Service, "/drone1"),
            "/drone1/cstep/evaluate"
        );
        assert_eq!(
            resolve("cstep/evaluate_batch", Service, "/drone1"),
            "/drone1/batch"
        );
        assert_eq!(
            resolve("cstep/evaluate_batch", Topic, "/drone1"),
            "/drone1/cstep/evaluate_batch"
        );
        assert_eq!(
            resolve("cstep/reward", Topic, "/drone1"),
            "/drone1/cstep_node/reward"
        );
        assert_eq!(
            resolve("cstep/reward", Service, "/drone1"),
            "/drone1/cstep/reward"
        );
    }

    #[test]
    fn names_longer_than_rcl_allows_are_refused_quoting_only_an_excerpt() {
        // Regression: a 60 000-character remap was accepted (rcl refuses a topic name over
        // 247 characters, a node name over 255, a namespace over 245), and errors quoted values
        // whole.
        let long = "a".repeat(60_000);
        let parsed = parse(&format!("--ros-args -r scan:={long}"));
        let e = parsed
            .resolve("scan", NameKind::Topic, "cstep_node", "/")
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "\"/{}… (60001 characters)\" has 60001 characters, more than the 247 rcl \
                 allows in a topic or service name",
                "a".repeat(79)
            )
        );
        let longest = "a".repeat(MAX_NAME_LENGTH - 1);
        let parsed = parse(&format!("--ros-args -r scan:={longest}"));
        let resolved = parsed.resolve("scan", NameKind::Topic, "cstep_node", "/");
        assert_eq!(resolved.unwrap().len(), MAX_NAME_LENGTH);
        // The namespace counts: the same name under /ns is too long.
        assert!(matches!(
            expand(&longest, "cstep_node", "/ns"),
            Err(NameError::TooLong(_))
        ));
        let node = |n: usize| format!("--ros-args -r __node:={}", "n".repeat(n));
        parse(&node(MAX_NODE_NAME_LENGTH));
        let e = error(&node(MAX_NODE_NAME_LENGTH + 1));
        assert!(
            e.ends_with("the node name has 256 characters, more than the 255 rcl allows"),
            "{e}"
        );
        let ns = |n: usize| format!("--ros-args -r __ns:=/{}", "n".repeat(n - 1));
        parse(&ns(MAX_NAMESPACE_LENGTH));
        let e = error(&ns(MAX_NAMESPACE_LENGTH + 1));
        assert!(
            e.ends_with("the namespace has 246 characters, more than the 245 rcl allows"),
            "{e}"
        );
        for line in [
            format!("--ros-args -r __node:={long}"),
            format!("--ros-args -r sc*n:={long}"),
            format!("--ros-args -r scan:={long}/-"),
            format!("--ros-args -p {long}-:=1"),
            format!("--ros-args --{long}"),
            long.clone(),
        ] {
            let e = error(&line);
            assert!(e.chars().count() < 400, "{} characters: {e}", e.len());
            assert!(e.contains("(60"), "says how long: {e}");
        }
    }

    #[test]
    fn malformed_rules_are_one_line_errors_naming_the_rule() {
        for (line, part) in [
            ("--ros-args -p seed", "'-p seed'"),
            ("--ros-args -p :=3", "invalid parameter name"),
            ("--ros-args -p a..b:=3", "invalid parameter name"),
            ("--ros-args -r scan", "'-r scan'"),
            ("--ros-args -r __ns:=drone1", "fully qualified"),
            ("--ros-args -r __ns:=/drone1/", "fully qualified"),
            ("--ros-args -r __node:=a/b", "invalid name"),
            ("--ros-args -r sc*n:=x", "wildcards"),
            ("--ros-args -r scan:=a//b", "replacement"),
            ("--ros-args --params-file", "needs a file path"),
            ("--ros-args --log-level loud", "not one of"),
            ("--ros-args --log-level :=debug", "logger name is empty"),
            ("--ros-args --log-level x:=loud", "not one of"),
            ("--ros-args -e", "needs an enclave"),
            ("--ros-args --verbose", "unknown ROS argument \"--verbose\""),
        ] {
            let e = error(line);
            assert!(e.contains(part), "{line}: {e}");
        }
    }

    #[test]
    fn each_malformed_rule_is_its_own_variant_with_rcls_words() {
        let rule = |line: &str| match RosArgs::parse(&args(line)) {
            Err(ArgsError::Rule { reason, .. }) => reason,
            other => panic!("{line}: {other:?}"),
        };
        assert_eq!(rule("--ros-args -p seed"), RuleError::ParamForm);
        assert_eq!(
            rule("--ros-args -r __ns:=drone1"),
            RuleError::Namespace("drone1".into())
        );
        assert_eq!(
            rule("--ros-args -r scan:=a//b"),
            RuleError::Name {
                side: Side::Replacement,
                name: "a//b".into(),
                reason: InvalidName::Token(String::new()),
            }
        );
        assert_eq!(
            RosArgs::parse(&args("--ros-args --log-level loud"))
                .unwrap_err()
                .to_string(),
            "--ros-args: couldn't parse log level: '--log-level loud': \
             not one of unset, debug, info, warn, error, fatal"
        );
        assert_eq!(
            RosArgs::parse(&args("--ros-args -e")),
            Err(ArgsError::MissingValue {
                flag: "-e".into(),
                what: "an enclave name"
            })
        );
    }

    #[test]
    fn a_replacement_that_does_not_expand_names_its_rule() {
        let parsed = parse("--ros-args -r odom:=1abc");
        let e = parsed
            .resolve("odom", NameKind::Topic, "cstep_node", "/")
            .unwrap_err();
        assert_eq!(
            e,
            NameError::Replacement {
                from: "odom".into(),
                to: "1abc".into(),
                expanded: "/1abc".into()
            }
        );
        assert_eq!(
            e.to_string(),
            format!(
                "remap rule odom:=1abc: {}",
                expand("1abc", "cstep_node", "/").unwrap_err()
            )
        );
    }
}
