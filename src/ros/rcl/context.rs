//! The DDS context every cstep program joins: `ROS_DOMAIN_ID`, `ROS_AUTOMATIC_DISCOVERY_RANGE`,
//! `ROS_STATIC_PEERS` and the deprecated `ROS_LOCALHOST_ONLY`, read from the environment exactly
//! as rcl (Jazzy) reads them — ros2-client reads none of them by itself.
//!
//! `cstep node`, `cstep echo` and `cstep demo` all start here, so they always meet on the same
//! domain with the same reach. The range is enforced on the sockets (`vendor/rustdds`, see its
//! `CSTEP_PATCH.md`): in `LOCALHOST` and `OFF` every socket is bound to `127.0.0.1` and no
//! datagram goes to or comes from another host.

use std::net::{IpAddr, ToSocketAddrs};

use ros2_client::dds::rustdds::{DiscoveryRange, DomainParticipantBuilder};
use ros2_client::Context;

use crate::excerpt::excerpt;

/// `ROS_AUTOMATIC_DISCOVERY_RANGE`: how far automatic discovery reaches (rmw's
/// `rmw_automatic_discovery_range_t`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Range {
    /// `SUBNET`, and the default when the variable is unset or empty (as in rcl 9.2, Jazzy):
    /// multicast discovery on every network interface.
    Subnet,
    /// `LOCALHOST`, and what an unknown value means (rcl warns): this machine only.
    Localhost,
    /// `OFF`: no discovery; no other process, even on this machine, can reach the node.
    Off,
    /// `SYSTEM_DEFAULT`: the middleware's own default, which for RustDDS (as for Fast DDS) is
    /// `SUBNET`.
    SystemDefault,
}

impl Range {
    /// The value of `ROS_AUTOMATIC_DISCOVERY_RANGE` that selects this range.
    pub fn name(self) -> &'static str {
        match self {
            Range::Subnet => "SUBNET",
            Range::Localhost => "LOCALHOST",
            Range::Off => "OFF",
            Range::SystemDefault => "SYSTEM_DEFAULT",
        }
    }

    /// What the range exposes, in a sentence for the start-up line.
    pub fn exposure(self, has_peers: bool) -> &'static str {
        match (self, has_peers) {
            (Range::Subnet | Range::SystemDefault, _) => {
                "multicast discovery on every network interface: any host on the networks can \
                 reach it"
            }
            (Range::Localhost, false) => "sockets on 127.0.0.1 only: no other host can reach it",
            (Range::Localhost, true) => {
                "this machine and the static peers only (ROS_STATIC_PEERS); other hosts are ignored"
            }
            (Range::Off, _) => {
                "no discovery: sockets on 127.0.0.1 only, and no other process can reach it"
            }
        }
    }

    /// The RustDDS range that enforces it.
    fn dds(self) -> DiscoveryRange {
        match self {
            Range::Subnet | Range::SystemDefault => DiscoveryRange::Subnet,
            Range::Localhost => DiscoveryRange::Localhost,
            Range::Off => DiscoveryRange::Off,
        }
    }
}

/// rmw's `RMW_DISCOVERY_OPTIONS_STATIC_PEERS_MAX_LENGTH`: a static peer is at most one less.
const STATIC_PEER_MAX_LENGTH: usize = 255;

/// Where discovery looks, as the ROS environment variables ask.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Discovery {
    /// `ROS_DOMAIN_ID` (0 when unset or empty).
    pub domain_id: u16,
    /// `ROS_AUTOMATIC_DISCOVERY_RANGE`, or `LOCALHOST` forced by `ROS_LOCALHOST_ONLY=1`.
    pub range: Range,
    /// `ROS_STATIC_PEERS`: hosts (names or addresses) also discovered by unicast. Empty in `OFF`
    /// range and under `ROS_LOCALHOST_ONLY=1`, which ignore them.
    pub static_peers: Vec<String>,
    /// Whether `ROS_AUTOMATIC_DISCOVERY_RANGE` was unset or empty (the range is then rcl's
    /// default, `SUBNET`).
    pub range_defaulted: bool,
    /// The warnings rcl logs for this environment, in its words, to print at start-up.
    pub warnings: Vec<String>,
}

/// Why the DDS context could not be set up from the environment.
#[derive(Debug, thiserror::Error)]
pub enum ContextError {
    /// `ROS_DOMAIN_ID` is not a domain rcl accepts; the value as set.
    #[error("ROS_DOMAIN_ID must be 0–232, got \"{}\"", excerpt(.0))]
    DomainId(String),
    /// A `ROS_STATIC_PEERS` entry names no IPv4 host.
    #[error("ROS_STATIC_PEERS: cannot resolve \"{}\"", excerpt(.0))]
    StaticPeer(String),
    /// RustDDS could not join the domain.
    #[error("cannot join DDS domain {domain}: {reason}")]
    JoinDomain {
        /// The domain.
        domain: u16,
        /// RustDDS's reason.
        #[source]
        reason: ros2_client::dds::rustdds::dds::CreateError,
    },
    /// ros2-client could not build its context on the participant.
    #[error("ROS context: {0}")]
    RosContext(#[source] ros2_client::CreateError),
}

impl Discovery {
    /// The settings of this process's environment.
    pub fn from_env() -> Result<Self, ContextError> {
        Self::from_vars(|name| std::env::var(name).ok())
    }

    /// The settings given a variable lookup, by rcl's rules (`rcl/src/rcl/init.c`,
    /// `discovery_options.c`, `localhost.c` in rcl 9.2): values are case-sensitive; an unknown
    /// range warns and means `LOCALHOST`; `ROS_LOCALHOST_ONLY` is deprecated (any non-empty
    /// value warns), and `1` forces `LOCALHOST` with no static peers; `ROS_STATIC_PEERS` splits
    /// on `;`, skips empty entries and, with a warning, entries over 255 bytes, and is not read
    /// in `OFF` range. An invalid `ROS_DOMAIN_ID` is an error naming it.
    pub fn from_vars(var: impl Fn(&str) -> Option<String>) -> Result<Self, ContextError> {
        let domain_id = match var("ROS_DOMAIN_ID") {
            Some(text) if !text.trim().is_empty() => text
                .trim()
                .parse::<u16>()
                .ok()
                .filter(|d| *d <= 232)
                .ok_or_else(|| ContextError::DomainId(text.clone()))?,
            _ => 0,
        };
        // rcutils_get_env gives "" for an unset variable; rcl treats the two alike.
        let value = |name: &str| var(name).unwrap_or_default();
        let mut warnings = Vec::new();
        let localhost_only = value("ROS_LOCALHOST_ONLY");
        if !localhost_only.is_empty() {
            warnings.push(
                "ROS_LOCALHOST_ONLY is deprecated but still honored if it is enabled. Use \
                 ROS_AUTOMATIC_DISCOVERY_RANGE and ROS_STATIC_PEERS instead."
                    .to_owned(),
            );
        }
        if localhost_only == "1" {
            warnings.push(
                "'localhost_only' is enabled, 'automatic_discovery_range' and 'static_peers' \
                 will be ignored."
                    .to_owned(),
            );
            return Ok(Self {
                domain_id,
                range: Range::Localhost,
                static_peers: Vec::new(),
                range_defaulted: false,
                warnings,
            });
        }
        if !localhost_only.is_empty() {
            warnings.push(
                "'localhost_only' is disabled, 'automatic_discovery_range' and 'static_peers' \
                 will be used."
                    .to_owned(),
            );
        }
        let name = value("ROS_AUTOMATIC_DISCOVERY_RANGE");
        let range = match name.as_str() {
            "" | "SUBNET" => Range::Subnet,
            "OFF" => Range::Off,
            "LOCALHOST" => Range::Localhost,
            "SYSTEM_DEFAULT" => Range::SystemDefault,
            other => {
                warnings.push(format!(
                    "Invalid value '{other}' specified for 'ROS_AUTOMATIC_DISCOVERY_RANGE', \
                     assuming localhost only"
                ));
                Range::Localhost
            }
        };
        let static_peers = if range == Range::Off {
            Vec::new()
        } else {
            value("ROS_STATIC_PEERS")
                .split(';')
                .filter(|peer| !peer.is_empty())
                .filter(|peer| {
                    let fits = peer.len() <= STATIC_PEER_MAX_LENGTH;
                    if !fits {
                        warnings.push(format!(
                            "Static peer {peer} specified to 'ROS_STATIC_PEERS' is too long \
                             (maximum of {STATIC_PEER_MAX_LENGTH}); skipping"
                        ));
                    }
                    fits
                })
                .map(str::to_owned)
                .collect()
        };
        Ok(Self {
            domain_id,
            range,
            static_peers,
            range_defaulted: name.is_empty(),
            warnings,
        })
    }

    /// One line saying how far this participant reaches and why, for start-up.
    pub fn describe(&self) -> String {
        let source = if self.range_defaulted {
            "ROS_AUTOMATIC_DISCOVERY_RANGE unset: rcl's default; set it to LOCALHOST to stay on \
             this machine"
        } else {
            "from the environment"
        };
        format!(
            "discovery range {} ({source}): {}",
            self.range.name(),
            self.range.exposure(!self.static_peers.is_empty())
        )
    }

    /// The static peers' IPv4 addresses, each name resolved to its first one (as rmw_fastrtps
    /// does); a peer that does not resolve is an error naming it.
    fn peer_addresses(&self) -> Result<Vec<IpAddr>, ContextError> {
        self.static_peers
            .iter()
            .map(|peer| {
                (peer.as_str(), 0)
                    .to_socket_addrs()
                    .ok()
                    .and_then(|mut found| found.find(|a| a.is_ipv4()))
                    .map(|a| a.ip())
                    .ok_or_else(|| ContextError::StaticPeer(peer.clone()))
            })
            .collect()
    }
}

/// A ros2-client context on the domain the environment names, reaching as far as it says.
/// Prints rcl's warnings for the environment, and [`Discovery::describe`]'s line when the range
/// was left to its default or `always_announce` is set (the node says its reach every time).
pub fn context_from_env(always_announce: bool) -> Result<Context, ContextError> {
    if std::env::var_os("ROS_DISTRO").is_none() {
        // ros2-client warns at start-up without it; cstep speaks Jazzy.
        std::env::set_var("ROS_DISTRO", "jazzy");
    }
    let discovery = Discovery::from_env()?;
    for warning in &discovery.warnings {
        eprintln!("cstep: warning: {warning}");
    }
    if always_announce || discovery.range_defaulted {
        eprintln!("cstep: {}", discovery.describe());
    }
    let domain = discovery.domain_id;
    let participant = DomainParticipantBuilder::new(domain)
        .automatic_discovery_range(discovery.range.dds())
        .with_static_peers(discovery.peer_addresses()?)
        .build()
        .map_err(|reason| ContextError::JoinDomain { domain, reason })?;
    Context::from_domain_participant(participant).map_err(ContextError::RosContext)
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
    fn defaults_to_domain_zero_on_every_network_as_rcl_does() {
        for unset in [vars(&[]), vars(&[("ROS_AUTOMATIC_DISCOVERY_RANGE", "")])] {
            let d = Discovery::from_vars(unset).unwrap();
            assert_eq!((d.domain_id, d.range), (0, Range::Subnet));
            assert!(d.range_defaulted && d.warnings.is_empty() && d.static_peers.is_empty());
            assert!(d.describe().contains("unset"), "{}", d.describe());
        }
        let d = Discovery::from_vars(vars(&[("ROS_DOMAIN_ID", " ")])).unwrap();
        assert_eq!(d.domain_id, 0);
    }

    #[test]
    fn reads_each_range_by_its_exact_name() {
        for (value, range) in [
            ("SUBNET", Range::Subnet),
            ("LOCALHOST", Range::Localhost),
            ("OFF", Range::Off),
            ("SYSTEM_DEFAULT", Range::SystemDefault),
        ] {
            let d = Discovery::from_vars(vars(&[
                ("ROS_DOMAIN_ID", " 42 "),
                ("ROS_AUTOMATIC_DISCOVERY_RANGE", value),
            ]))
            .unwrap();
            assert_eq!((d.domain_id, d.range), (42, range));
            assert!(!d.range_defaulted && d.warnings.is_empty(), "{value}");
            assert_eq!(range.name(), value);
        }
    }

    #[test]
    fn unknown_and_lowercase_ranges_warn_and_mean_localhost() {
        for value in ["localhost", "off", "Subnet", "LAN", " LOCALHOST"] {
            let d =
                Discovery::from_vars(vars(&[("ROS_AUTOMATIC_DISCOVERY_RANGE", value)])).unwrap();
            assert_eq!(d.range, Range::Localhost, "{value}");
            assert_eq!(
                d.warnings,
                [format!(
                    "Invalid value '{value}' specified for 'ROS_AUTOMATIC_DISCOVERY_RANGE', \
                     assuming localhost only"
                )]
            );
        }
    }

    #[test]
    fn localhost_only_is_deprecated_and_1_overrides_range_and_peers() {
        let d = Discovery::from_vars(vars(&[
            ("ROS_LOCALHOST_ONLY", "1"),
            ("ROS_AUTOMATIC_DISCOVERY_RANGE", "SUBNET"),
            ("ROS_STATIC_PEERS", "192.0.2.9"),
        ]))
        .unwrap();
        assert_eq!(d.range, Range::Localhost);
        assert!(d.static_peers.is_empty());
        assert_eq!(d.warnings.len(), 2);
        assert!(d.warnings[0].starts_with("ROS_LOCALHOST_ONLY is deprecated"));
        assert!(d.warnings[1].starts_with("'localhost_only' is enabled"));
        // Any other non-empty value is "disabled": deprecated, and the range rules.
        let d = Discovery::from_vars(vars(&[
            ("ROS_LOCALHOST_ONLY", "0"),
            ("ROS_AUTOMATIC_DISCOVERY_RANGE", "OFF"),
        ]))
        .unwrap();
        assert_eq!(d.range, Range::Off);
        assert_eq!(d.warnings.len(), 2);
        assert!(d.warnings[1].starts_with("'localhost_only' is disabled"));
        let d = Discovery::from_vars(vars(&[("ROS_LOCALHOST_ONLY", "")])).unwrap();
        assert!(d.warnings.is_empty() && d.range == Range::Subnet);
    }

    #[test]
    fn static_peers_split_like_rcutils_and_are_ignored_when_off() {
        let long = "h".repeat(256);
        let peers = format!(";192.0.2.9;;localhost;{long};");
        let d = Discovery::from_vars(vars(&[
            ("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST"),
            ("ROS_STATIC_PEERS", &peers),
        ]))
        .unwrap();
        assert_eq!(d.static_peers, ["192.0.2.9", "localhost"]);
        assert_eq!(d.warnings.len(), 1);
        assert!(d.warnings[0].contains("is too long (maximum of 255); skipping"));
        assert_eq!(
            d.peer_addresses().unwrap(),
            [
                "192.0.2.9".parse::<IpAddr>().unwrap(),
                [127, 0, 0, 1].into()
            ]
        );
        assert!(d.describe().contains("static peers"));
        let d = Discovery::from_vars(vars(&[
            ("ROS_AUTOMATIC_DISCOVERY_RANGE", "OFF"),
            ("ROS_STATIC_PEERS", "192.0.2.9"),
        ]))
        .unwrap();
        assert!(d.static_peers.is_empty());
        let d =
            Discovery::from_vars(vars(&[("ROS_STATIC_PEERS", "no.such.host.invalid")])).unwrap();
        let err = d.peer_addresses().unwrap_err().to_string();
        assert!(err.contains("no.such.host.invalid"), "{err}");
    }

    #[test]
    fn a_bad_domain_id_is_an_error_naming_the_variable_and_value() {
        for bad in ["233", "-1", "seven", "1.5"] {
            let err = Discovery::from_vars(vars(&[("ROS_DOMAIN_ID", bad)]))
                .unwrap_err()
                .to_string();
            assert!(err.contains("ROS_DOMAIN_ID") && err.contains(bad), "{err}");
        }
        // A long value is quoted by its start and length.
        let long = "9".repeat(120_000);
        let err = Discovery::from_vars(vars(&[("ROS_DOMAIN_ID", &long)])).unwrap_err();
        assert!(
            err.to_string().ends_with("… (120000 characters)\""),
            "{err}"
        );
        assert!(err.to_string().len() < 200, "{err}");
    }

    #[test]
    fn relative_names_resolve_into_the_namespace() {
        assert_eq!(resolve("/", "scan"), "/scan");
        assert_eq!(resolve("/robot", "scan"), "/robot/scan");
        assert_eq!(resolve("/robot/", "scan"), "/robot/scan");
        assert_eq!(resolve("/robot", "/diagnostics"), "/diagnostics");
    }
}
