//! The watch for another node answering under this node's names.

use std::time::Instant;

use ros2_client::dds::rustdds::{RTPSEntity, GUID};

use crate::ros::rivals::{self, Claims, Participant, Verdict};

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
        let own = participant(self.participant.guid());
        let writers = self.participant.discovered_writers();
        let rivals = self.claims.rivals(
            writers.iter().map(|w| {
                (
                    w.publication_topic_data.topic_name.as_str(),
                    participant(w.writer_proxy.remote_writer_guid),
                )
            }),
            &own,
        );
        rivals::verdict(
            &rivals,
            &own,
            self.started.elapsed(),
            &self.node,
            self.domain,
        )
    }
}

/// The participant of an entity's GUID, with its creation time where the GUID's prefix carries
/// one.
fn participant(guid: GUID) -> Participant {
    Participant {
        id: format!("{:?}", guid.prefix),
        created_ms: guid.prefix.creation_millis(),
    }
}
