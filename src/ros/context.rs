//! The DDS context every cstep program joins: `ROS_DOMAIN_ID` and localhost-only discovery, read
//! from the environment as rcl reads them (ros2-client reads neither by itself).
//!
//! `cstep node` and `cstep echo` both start here, so they always meet on the same domain and
//! never leave the machine when the environment says localhost.

use std::net::Ipv4Addr;

use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::Context;

/// Where discovery looks, as the ROS environment variables ask.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Discovery {
    /// `ROS_DOMAIN_ID` (0 when unset or empty).
    pub domain_id: u16,
    /// Localhost only: `ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`, or the deprecated
    /// `ROS_LOCALHOST_ONLY=1`.
    pub localhost_only: bool,
}

impl Discovery {
    /// The settings of this process's environment.
    pub fn from_env() -> Result<Self, String> {
        Self::from_vars(|name| std::env::var(name).ok())
    }

    /// The settings given a variable lookup; an invalid `ROS_DOMAIN_ID` is an error naming it.
    pub fn from_vars(var: impl Fn(&str) -> Option<String>) -> Result<Self, String> {
        let domain_id = match var("ROS_DOMAIN_ID") {
            Some(text) if !text.trim().is_empty() => text
                .trim()
                .parse::<u16>()
                .ok()
                .filter(|d| *d <= 232)
                .ok_or_else(|| format!("ROS_DOMAIN_ID must be 0–232, got \"{text}\""))?,
            _ => 0,
        };
        let localhost_only = var("ROS_AUTOMATIC_DISCOVERY_RANGE").is_some_and(|v| v == "LOCALHOST")
            || var("ROS_LOCALHOST_ONLY").is_some_and(|v| v == "1");
        Ok(Self {
            domain_id,
            localhost_only,
        })
    }
}

/// A ros2-client context on the domain the environment names, localhost-only when it asks.
pub fn context_from_env() -> Result<Context, String> {
    if std::env::var_os("ROS_DISTRO").is_none() {
        // ros2-client warns at start-up without it; cstep speaks Jazzy.
        std::env::set_var("ROS_DISTRO", "jazzy");
    }
    let discovery = Discovery::from_env()?;
    let domain = discovery.domain_id;
    let mut builder = DomainParticipantBuilder::new(domain);
    if discovery.localhost_only {
        builder = builder.with_only_networks([Ipv4Addr::LOCALHOST]);
    }
    let participant = builder
        .build()
        .map_err(|e| format!("cannot join DDS domain {domain}: {e:?}"))?;
    Context::from_domain_participant(participant).map_err(|e| format!("ROS context: {e:?}"))
}

/// The absolute form of a topic or service name: relative names live in `namespace`.
/// (ros2-client's own resolution writes `rt//scan` for the root namespace.)
pub fn resolve(namespace: &str, name: &str) -> String {
    if name.starts_with('/') {
        name.to_owned()
    } else {
        format!("{}/{name}", namespace.trim_end_matches('/'))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vars(pairs: &[(&str, &str)]) -> impl Fn(&str) -> Option<String> {
        let owned: Vec<(String, String)> = pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        move |name| {
            owned
                .iter()
                .find(|(k, _)| k == name)
                .map(|(_, v)| v.clone())
        }
    }

    #[test]
    fn defaults_to_domain_zero_on_every_network() {
        let d = Discovery::from_vars(vars(&[])).unwrap();
        assert_eq!(
            d,
            Discovery {
                domain_id: 0,
                localhost_only: false
            }
        );
        let d = Discovery::from_vars(vars(&[("ROS_DOMAIN_ID", " ")])).unwrap();
        assert_eq!(d.domain_id, 0);
    }

    #[test]
    fn reads_the_domain_and_both_localhost_spellings() {
        let d = Discovery::from_vars(vars(&[
            ("ROS_DOMAIN_ID", " 42 "),
            ("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST"),
        ]))
        .unwrap();
        assert_eq!(
            d,
            Discovery {
                domain_id: 42,
                localhost_only: true
            }
        );
        let d = Discovery::from_vars(vars(&[("ROS_LOCALHOST_ONLY", "1")])).unwrap();
        assert!(d.localhost_only);
        let d = Discovery::from_vars(vars(&[("ROS_AUTOMATIC_DISCOVERY_RANGE", "SUBNET")])).unwrap();
        assert!(!d.localhost_only);
    }

    #[test]
    fn a_bad_domain_id_is_an_error_naming_the_variable_and_value() {
        for bad in ["233", "-1", "seven", "1.5"] {
            let err = Discovery::from_vars(vars(&[("ROS_DOMAIN_ID", bad)])).unwrap_err();
            assert!(err.contains("ROS_DOMAIN_ID") && err.contains(bad), "{err}");
        }
    }

    #[test]
    fn relative_names_resolve_into_the_namespace() {
        assert_eq!(resolve("/", "scan"), "/scan");
        assert_eq!(resolve("/robot", "scan"), "/robot/scan");
        assert_eq!(resolve("/robot/", "scan"), "/robot/scan");
        assert_eq!(resolve("/robot", "/diagnostics"), "/diagnostics");
    }
}
