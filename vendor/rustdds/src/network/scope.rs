// cstep patch: the whole file (see CSTEP_PATCH.md).
//
// How far a participant reaches, as ROS 2 says it with `ROS_AUTOMATIC_DISCOVERY_RANGE` and
// `ROS_STATIC_PEERS`, enforced on the sockets rather than only on what is advertised.

use std::{
  net::{IpAddr, Ipv4Addr, SocketAddr},
  sync::Arc,
};

use crate::network::util::local_interface_table;

/// How far automatic discovery reaches: ROS 2's `ROS_AUTOMATIC_DISCOVERY_RANGE`, with the
/// meanings `rmw_fastrtps` gives its values, enforced on the sockets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DiscoveryRange {
  /// Multicast discovery on every interface (or those given to
  /// `with_only_networks`): the RTPS default.
  #[default]
  Subnet,
  /// This host only: no multicast; SPDP goes to the well-known ports on
  /// `127.0.0.1` (and to static peers). Without static peers every socket is
  /// bound to `127.0.0.1`; with them, datagrams from or to any address but
  /// this host's and the peers' are dropped.
  Localhost,
  /// No discovery at all: every socket is bound to `127.0.0.1`, no SPDP is
  /// sent, and no datagram is exchanged with any other participant.
  Off,
}

/// Which remote addresses a participant may exchange datagrams with, and how
/// it binds its sockets: a [`DiscoveryRange`] with its static peers.
#[derive(Debug, Clone, Default)]
pub(crate) struct PeerScope {
  range: DiscoveryRange,
  /// Static peers (unicast SPDP destinations).
  peers: Arc<[IpAddr]>,
  /// Besides loopback, the addresses a `Localhost` participant talks to: this
  /// host's own interface addresses and the static peers.
  allowed: Arc<[IpAddr]>,
}

impl PeerScope {
  /// The scope of `range` with `static_peers` (ignored when `range` is `Off`,
  /// as ROS 2 ignores them).
  pub(crate) fn new(range: DiscoveryRange, static_peers: &[IpAddr]) -> Self {
    let peers: Arc<[IpAddr]> = match range {
      DiscoveryRange::Off => Arc::new([]),
      _ => static_peers.into(),
    };
    let allowed: Arc<[IpAddr]> = match range {
      DiscoveryRange::Localhost => local_interface_table()
        .iter()
        .map(|iface| iface.ip)
        .chain(peers.iter().copied())
        .collect(),
      _ => Arc::new([]),
    };
    Self {
      range,
      peers,
      allowed,
    }
  }

  /// The range this scope enforces.
  pub(crate) fn range(&self) -> DiscoveryRange {
    self.range
  }

  /// The static peers, to which SPDP is announced by unicast.
  pub(crate) fn static_peers(&self) -> &[IpAddr] {
    &self.peers
  }

  /// Whether multicast sockets are opened (and multicast locators used).
  pub(crate) fn multicast(&self) -> bool {
    self.range == DiscoveryRange::Subnet
  }

  /// Whether every socket is bound to the loopback address only.
  pub(crate) fn loopback_only(&self) -> bool {
    match self.range {
      DiscoveryRange::Subnet => false,
      DiscoveryRange::Localhost => self.peers.is_empty(),
      DiscoveryRange::Off => true,
    }
  }

  /// The address every unicast socket binds to.
  pub(crate) fn bind_address(&self) -> IpAddr {
    if self.loopback_only() {
      IpAddr::V4(Ipv4Addr::LOCALHOST)
    } else {
      IpAddr::V4(Ipv4Addr::UNSPECIFIED)
    }
  }

  /// Whether a datagram may be sent to, or accepted from, `ip`.
  pub(crate) fn allows(&self, ip: IpAddr) -> bool {
    match self.range {
      DiscoveryRange::Subnet => true,
      DiscoveryRange::Localhost => ip.is_loopback() || self.allowed.contains(&ip),
      DiscoveryRange::Off => false,
    }
  }

  /// Whether a received datagram from `source` is accepted: outside `Subnet`,
  /// one whose source is unknown is not.
  pub(crate) fn accepts(&self, source: Option<SocketAddr>) -> bool {
    self.range == DiscoveryRange::Subnet || source.is_some_and(|s| self.allows(s.ip()))
  }
}

#[cfg(test)]
mod tests {
  use super::*;

  const REMOTE: IpAddr = IpAddr::V4(Ipv4Addr::new(203, 0, 113, 7));
  const PEER: IpAddr = IpAddr::V4(Ipv4Addr::new(198, 51, 100, 9));

  fn from(ip: IpAddr) -> Option<SocketAddr> {
    Some(SocketAddr::new(ip, 7410))
  }

  #[test]
  fn subnet_reaches_everyone_on_every_interface() {
    let scope = PeerScope::new(DiscoveryRange::Subnet, &[PEER]);
    assert!(scope.multicast() && !scope.loopback_only());
    assert!(scope.bind_address().is_unspecified());
    assert!(scope.accepts(from(REMOTE)) && scope.accepts(None));
    assert_eq!(scope.static_peers(), &[PEER]);
  }

  #[test]
  fn localhost_without_peers_binds_loopback_and_refuses_other_hosts() {
    let scope = PeerScope::new(DiscoveryRange::Localhost, &[]);
    assert!(!scope.multicast() && scope.loopback_only());
    assert_eq!(scope.bind_address(), IpAddr::V4(Ipv4Addr::LOCALHOST));
    assert!(scope.accepts(from(IpAddr::V4(Ipv4Addr::LOCALHOST))));
    assert!(!scope.accepts(from(REMOTE)) && !scope.accepts(None));
    assert!(!scope.allows(REMOTE));
  }

  #[test]
  fn localhost_with_peers_binds_every_interface_but_talks_to_the_peers_only() {
    let scope = PeerScope::new(DiscoveryRange::Localhost, &[PEER]);
    assert!(!scope.multicast() && !scope.loopback_only());
    assert!(scope.bind_address().is_unspecified());
    assert!(scope.accepts(from(PEER)) && scope.allows(PEER));
    assert!(!scope.accepts(from(REMOTE)) && !scope.allows(REMOTE));
    assert!(scope.allows(IpAddr::V4(Ipv4Addr::LOCALHOST)));
  }

  #[test]
  fn off_talks_to_nobody_and_ignores_peers() {
    let scope = PeerScope::new(DiscoveryRange::Off, &[PEER]);
    assert!(!scope.multicast() && scope.loopback_only());
    assert!(scope.static_peers().is_empty());
    assert!(!scope.accepts(from(IpAddr::V4(Ipv4Addr::LOCALHOST))));
    assert!(!scope.allows(PEER));
  }
}
