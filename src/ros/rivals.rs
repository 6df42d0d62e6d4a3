//! Another participant answering under this node's names, found from what DDS discovery reports.
//!
//! Two nodes that publish the same `cstep/empowerment` or serve the same `cstep/evaluate` on one
//! domain both answer every scan and every request, and a subscriber or a client gets a mix of
//! the two without any sign of it. DDS does not forbid that, and rclcpp only warns about a
//! duplicate node name, so the node looks for it itself: in the writers that DDS discovery
//! (SEDP) reports, any writer of another participant on one of the topics this node alone
//! should write — its two score topics, and the reply topics of its two services — is a rival.
//!
//! What the node does about one ([`Verdict`]): DDS discovery cannot prove that nobody else is on
//! the domain (it takes 1–4 s, and a participant that has not been heard from yet is simply
//! absent), so the node does not wait before it serves; it checks continuously from the start.
//! A rival found within [`STARTUP_WINDOW`] of the start means this node is the newcomer, or
//! started together with the other: it stops with a one-line error and exit code 1, so the node
//! that was already serving goes on alone. A rival found later is a newcomer: the node warns on
//! stderr and in its diagnostics (level ERROR, naming the rival) as long as the rival is there
//! — as rclcpp does for a duplicate node name — and keeps serving, since stopping would leave
//! the newcomer's clients (a cstep node newcomer stops by itself) with nobody.

use std::collections::BTreeSet;
use std::time::Duration;

/// How long after its start a node that finds a rival refuses to go on (exits 1). Discovery
/// between two processes on localhost takes 1–2 s, occasionally 4 s; on a loaded machine more.
pub const STARTUP_WINDOW: Duration = Duration::from_secs(10);

/// How often the node looks at the writers discovery has reported.
pub const CHECK_PERIOD: Duration = Duration::from_millis(250);

/// The DDS topics whose writers should all be this node's: `rt/<topic>` for a published topic,
/// `rr/<service>Reply` for a served service (the ROS 2 name mangling, as ros2-client and rmw
/// use it), each with the ROS name it stands for.
#[derive(Debug, Clone, Default)]
pub struct Claims {
    /// (DDS topic name, what it is in ROS terms, for messages).
    topics: Vec<(String, String)>,
}

impl Claims {
    /// No claims yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Claims the absolute ROS topic `name` (this node publishes it).
    pub fn topic(mut self, name: &str) -> Self {
        self.topics
            .push((format!("rt{name}"), format!("publishes {name}")));
        self
    }

    /// Claims the absolute ROS service `name` (this node serves it): its reply topic.
    pub fn service(mut self, name: &str) -> Self {
        self.topics
            .push((format!("rr{name}Reply"), format!("serves {name}")));
        self
    }

    /// The rivals among discovered writers, each given as its DDS topic name and the GUID prefix
    /// of its participant (as text); `own` is this node's participant, whose writers are not
    /// rivals. One [`Rival`] per participant, naming every claim it infringes, in order.
    pub fn rivals<'a>(
        &self,
        writers: impl IntoIterator<Item = (&'a str, String)>,
        own: &str,
    ) -> Vec<Rival> {
        let mut found: Vec<Rival> = Vec::new();
        let mut seen = BTreeSet::new();
        for (topic, participant) in writers {
            if participant == own {
                continue;
            }
            let Some((_, what)) = self.topics.iter().find(|(dds, _)| dds == topic) else {
                continue;
            };
            if !seen.insert((participant.clone(), what.clone())) {
                continue;
            }
            match found.iter_mut().find(|r| r.participant == participant) {
                Some(rival) => rival.claims.push(what.clone()),
                None => found.push(Rival {
                    participant,
                    claims: vec![what.clone()],
                }),
            }
        }
        for rival in &mut found {
            rival.claims.sort_by_key(|what| {
                self.topics
                    .iter()
                    .position(|(_, w)| w == what)
                    .unwrap_or(usize::MAX)
            });
        }
        found
    }
}

/// Another participant writing on topics this node claims.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rival {
    /// Its DDS participant (GUID prefix, hex).
    pub participant: String,
    /// What it does that this node does ("serves /cstep/evaluate", ...).
    pub claims: Vec<String>,
}

impl Rival {
    /// The rival in one line: "participant 0102… also serves /cstep/evaluate and publishes …".
    pub fn describe(&self) -> String {
        format!(
            "participant {} also {}",
            self.participant,
            self.claims.join(" and ")
        )
    }
}

/// What to do about the rivals found at some time since the start.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verdict {
    /// Nobody else: serve.
    Alone,
    /// A rival within the start-up window: stop with this error line.
    Refuse(String),
    /// A rival after the start-up window: go on, warning with this line.
    Warn(String),
}

/// The verdict on `rivals` found `since_start` after this node (`node`, its fully qualified
/// name, on `domain`) started.
pub fn verdict(rivals: &[Rival], since_start: Duration, node: &str, domain: u16) -> Verdict {
    let Some(first) = rivals.first() else {
        return Verdict::Alone;
    };
    let others = match rivals.len() {
        1 => String::new(),
        n => format!(" (and {} other participants)", n - 1),
    };
    if since_start < STARTUP_WINDOW {
        Verdict::Refuse(format!(
            "another node is already answering on ROS_DOMAIN_ID {domain}: {}{others}; \
             refusing to run {node} beside it, as their answers would mix (stop the other, \
             or use another ROS_DOMAIN_ID, namespace or remapping)",
            first.describe()
        ))
    } else {
        Verdict::Warn(format!(
            "another node started answering beside {node} on ROS_DOMAIN_ID {domain}: {}{others}; \
             subscribers and clients get answers from both",
            first.describe()
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn claims() -> Claims {
        Claims::new()
            .topic("/cstep/empowerment")
            .topic("/cstep/reward")
            .service("/cstep/evaluate")
            .service("/cstep/evaluate_batch")
    }

    #[test]
    fn writers_of_other_participants_on_claimed_topics_are_rivals() {
        let writers = [
            ("rt/cstep/empowerment", "aa".to_owned()),
            ("rr/cstep/evaluateReply", "bb".to_owned()),
            ("rt/cstep/reward", "bb".to_owned()),
            ("rr/cstep/evaluateReply", "bb".to_owned()), // a second server in one participant
            ("rt/cstep/empowerment", "own".to_owned()),
            ("rt/diagnostics", "cc".to_owned()),
            ("rq/cstep/evaluateRequest", "dd".to_owned()), // a client, not a server
            ("rt/cstep/empowerment_other", "ee".to_owned()),
        ];
        let rivals = claims().rivals(writers.iter().map(|(t, p)| (*t, p.clone())), "own");
        assert_eq!(
            rivals,
            [
                Rival {
                    participant: "aa".into(),
                    claims: vec!["publishes /cstep/empowerment".into()],
                },
                Rival {
                    participant: "bb".into(),
                    claims: vec![
                        "publishes /cstep/reward".into(),
                        "serves /cstep/evaluate".into()
                    ],
                },
            ]
        );
        assert_eq!(
            rivals[1].describe(),
            "participant bb also publishes /cstep/reward and serves /cstep/evaluate"
        );
    }

    #[test]
    fn a_rival_at_start_refuses_later_warns() {
        let rival = Rival {
            participant: "0102".into(),
            claims: vec!["serves /cstep/evaluate".into()],
        };
        assert_eq!(
            verdict(&[], Duration::ZERO, "/cstep_node", 7),
            Verdict::Alone
        );
        let Verdict::Refuse(line) = verdict(
            &[rival.clone(), rival.clone()],
            Duration::from_secs(1),
            "/cstep_node",
            7,
        ) else {
            panic!("a rival at start refuses");
        };
        assert!(!line.contains('\n'), "{line}");
        for part in [
            "ROS_DOMAIN_ID 7",
            "participant 0102 also serves /cstep/evaluate",
            "and 1 other",
            "/cstep_node",
        ] {
            assert!(line.contains(part), "{part}: {line}");
        }
        let Verdict::Warn(line) = verdict(
            std::slice::from_ref(&rival),
            STARTUP_WINDOW,
            "/cstep_node",
            7,
        ) else {
            panic!("a rival after the window warns");
        };
        assert!(line.contains("answers from both"), "{line}");
    }
}
