//! The watch for another node answering under this node's names.

use std::time::Instant;

use ros2_client::dds::rustdds::RTPSEntity;

use crate::ros::rivals::{self, Claims, Verdict};

/// Watches DDS discovery for another participant answering under this node's names
/// ([`crate::ros::rivals`]).
pub(super) struct Guard {
    pub(super) claims: Claims,
    pub(super) participant: ros2_client::dds::rustdds::DomainParticipant,
    pub(super) started: Instant,
    /// This node's fully qualified name and domain, for the messages.
    pub(super) node: String,
    pub(super) domain: u16,
}

impl Guard {
    /// The verdict on the writers discovery has reported so far.
    pub(super) fn check(&self) -> Verdict {
        let own = format!("{:?}", self.participant.guid().prefix);
        let writers = self.participant.discovered_writers();
        let rivals = self.claims.rivals(
            writers.iter().map(|w| {
                (
                    w.publication_topic_data.topic_name.as_str(),
                    format!("{:?}", w.writer_proxy.remote_writer_guid.prefix),
                )
            }),
            &own,
        );
        rivals::verdict(&rivals, self.started.elapsed(), &self.node, self.domain)
    }
}
