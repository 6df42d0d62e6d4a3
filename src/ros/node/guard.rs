//! The watch for another node answering under this node's names.

use std::time::Instant;

use ros2_client::dds::rustdds::discovery::DiscoveredWriterData;
use ros2_client::dds::rustdds::{RTPSEntity, GUID};

use super::rivals::{self, Claims, Endpoint, Participant, Verdict};

/// Watches DDS discovery for another participant answering under this node's names
/// ([`rivals`]).
pub(super) struct Guard {
    pub(super) claims: Claims,
    pub(super) participant: ros2_client::dds::rustdds::DomainParticipant,
    pub(super) started: Instant,
    /// This node's fully qualified name and domain, for the messages.
    pub(super) node: String,
    pub(super) domain: u16,
}

impl Guard {
    /// What discovery has reported so far, read once: the verdict on the writers, and the
    /// claimed topics the graph uses with another type ([`Claims::clashes`]) in one line (None
    /// while there are none).
    pub(super) fn check(&self) -> (Verdict, Option<String>) {
        let own = participant(self.participant.guid());
        let writers = self.participant.discovered_writers();
        let readers = self.participant.discovered_readers();
        let rivals = self.claims.rivals(writer_endpoints(&writers), &own);
        let verdict = rivals::verdict(
            &rivals,
            &own,
            self.started.elapsed(),
            &self.node,
            self.domain,
        );
        let endpoints = writer_endpoints(&writers).chain(readers.iter().map(|r| Endpoint {
            topic: r.subscription_topic_data.topic_name.as_str(),
            type_name: r.subscription_topic_data.type_name().as_str(),
            participant: participant(r.reader_proxy.remote_reader_guid),
        }));
        let clashes = self.claims.clashes(endpoints, &own);
        (verdict, (!clashes.is_empty()).then(|| clashes.join("; ")))
    }
}

/// Discovered writers as [`Endpoint`]s.
fn writer_endpoints(writers: &[DiscoveredWriterData]) -> impl Iterator<Item = Endpoint<'_>> {
    writers.iter().map(|w| Endpoint {
        topic: w.publication_topic_data.topic_name.as_str(),
        type_name: w.publication_topic_data.type_name.as_str(),
        participant: participant(w.writer_proxy.remote_writer_guid),
    })
}

/// The participant of an entity's GUID, with its creation time where the GUID's prefix carries
/// one.
fn participant(guid: GUID) -> Participant {
    Participant {
        id: format!("{:?}", guid.prefix),
        created_ms: guid.prefix.creation_millis(),
    }
}
