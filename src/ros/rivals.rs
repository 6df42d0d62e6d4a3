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
//! The older of two participants keeps serving and the newcomer stops with a one-line error and
//! exit code 1, whatever the gap between their starts: a cstep node's participant carries its
//! creation time in its GUID prefix (vendor/rustdds/CSTEP_PATCH.md, section 5), so both read
//! the same order from discovery data, and two created in the same millisecond are ordered by
//! their prefixes. A rival whose age is unknown (another DDS implementation) counts as older
//! within [`STARTUP_WINDOW`] of this node's start and as a newcomer after it. Facing a newcomer
//! the node warns on stderr and in its diagnostics (level ERROR, naming the rival) as long as the
//! rival is there — as rclcpp does for a duplicate node name — and keeps serving, since stopping
//! would leave the newcomer's clients (a cstep newcomer stops by itself) with nobody.

use std::collections::BTreeSet;
use std::time::Duration;

/// How long after its start a node that finds a rival of unknown age refuses to go on (exits
/// 1). Discovery between two processes on localhost takes 1–2 s, occasionally 4 s; on a loaded
/// machine more.
pub const STARTUP_WINDOW: Duration = Duration::from_secs(10);

/// How far apart two creation times may be and still be read as such: an unpatched RustDDS
/// fills the bytes that carry the time with random data, which lands this close to a real
/// time about once in 50 000 participants (a 60-day window in 2⁴⁸ ms).
const PLAUSIBLE_AGE_GAP_MS: u64 = 30 * 24 * 3600 * 1000;

/// A DDS participant as discovery reports it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Participant {
    /// Its GUID prefix, hex.
    pub id: String,
    /// When it was created (Unix milliseconds), where its GUID prefix carries that.
    pub created_ms: Option<u64>,
}

impl Participant {
    /// Whether `self` started before `own` (this node's participant): by creation times where
    /// both are known and plausible, ties broken by the prefixes; otherwise (an age unknown) as
    /// long as this node is within its start-up window, `since_start`.
    fn is_older_than(&self, own: &Participant, since_start: Duration) -> bool {
        match (self.created_ms, own.created_ms) {
            (Some(theirs), Some(ours)) if theirs.abs_diff(ours) <= PLAUSIBLE_AGE_GAP_MS => {
                (theirs, &self.id) < (ours, &own.id)
            }
            _ => since_start < STARTUP_WINDOW,
        }
    }
}

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

    /// The rivals among discovered writers, each given as its DDS topic name and its
    /// participant; `own` is this node's participant, whose writers are not rivals. One
    /// [`Rival`] per participant, naming every claim it infringes, in order.
    pub fn rivals<'a>(
        &self,
        writers: impl IntoIterator<Item = (&'a str, Participant)>,
        own: &Participant,
    ) -> Vec<Rival> {
        let mut found: Vec<Rival> = Vec::new();
        let mut seen = BTreeSet::new();
        for (topic, participant) in writers {
            if participant.id == own.id {
                continue;
            }
            let Some((_, what)) = self.topics.iter().find(|(dds, _)| dds == topic) else {
                continue;
            };
            if !seen.insert((participant.id.clone(), what.clone())) {
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
    /// Its DDS participant.
    pub participant: Participant,
    /// What it does that this node does ("serves /cstep/evaluate", ...).
    pub claims: Vec<String>,
}

impl Rival {
    /// The rival in one line: "participant 0102… also serves /cstep/evaluate and publishes …".
    pub fn describe(&self) -> String {
        format!(
            "participant {} also {}",
            self.participant.id,
            self.claims.join(" and ")
        )
    }
}

/// What to do about the rivals found at some time since the start.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verdict {
    /// Nobody else: serve.
    Alone,
    /// An older rival: stop with this error line.
    Refuse(String),
    /// Only newcomers: go on, warning with this line.
    Warn(String),
}

/// The verdict on `rivals` of this node (`own`, its participant; `node`, its fully qualified
/// name, on `domain`), found `since_start` after it started.
pub fn verdict(
    rivals: &[Rival],
    own: &Participant,
    since_start: Duration,
    node: &str,
    domain: u16,
) -> Verdict {
    let Some(first) = rivals.first() else {
        return Verdict::Alone;
    };
    let others = match rivals.len() {
        1 => String::new(),
        n => format!(" (and {} other participants)", n - 1),
    };
    if let Some(older) = rivals
        .iter()
        .find(|r| r.participant.is_older_than(own, since_start))
    {
        Verdict::Refuse(format!(
            "another node is already answering on ROS_DOMAIN_ID {domain}: {}{others}; \
             refusing to run {node} beside it, as their answers would mix (stop the other, \
             or use another ROS_DOMAIN_ID, namespace or remapping)",
            older.describe()
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

    fn participant(id: &str, created_ms: Option<u64>) -> Participant {
        Participant {
            id: id.into(),
            created_ms,
        }
    }

    fn rival(id: &str, created_ms: Option<u64>) -> Rival {
        Rival {
            participant: participant(id, created_ms),
            claims: vec!["serves /cstep/evaluate".into()],
        }
    }

    #[test]
    fn writers_of_other_participants_on_claimed_topics_are_rivals() {
        let writers = [
            ("rt/cstep/empowerment", "aa"),
            ("rr/cstep/evaluateReply", "bb"),
            ("rt/cstep/reward", "bb"),
            ("rr/cstep/evaluateReply", "bb"), // a second server in one participant
            ("rt/cstep/empowerment", "own"),
            ("rt/diagnostics", "cc"),
            ("rq/cstep/evaluateRequest", "dd"), // a client, not a server
            ("rt/cstep/empowerment_other", "ee"),
        ];
        let rivals = claims().rivals(
            writers.iter().map(|(t, p)| (*t, participant(p, None))),
            &participant("own", None),
        );
        assert_eq!(
            rivals,
            [
                Rival {
                    participant: participant("aa", None),
                    claims: vec!["publishes /cstep/empowerment".into()],
                },
                Rival {
                    participant: participant("bb", None),
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
    fn a_rival_of_unknown_age_at_start_refuses_later_warns() {
        let own = participant("own", Some(1_000_000));
        let rival = rival("0102", None);
        assert_eq!(
            verdict(&[], &own, Duration::ZERO, "/cstep_node", 7),
            Verdict::Alone
        );
        let Verdict::Refuse(line) = verdict(
            &[rival.clone(), rival.clone()],
            &own,
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
            &own,
            STARTUP_WINDOW,
            "/cstep_node",
            7,
        ) else {
            panic!("a rival after the window warns");
        };
        assert!(line.contains("answers from both"), "{line}");
    }

    /// Two nodes started 6 s apart, each inside its start-up window when it saw the other:
    /// before creation times were compared, whichever saw the other first quit — in one of two
    /// runs the one already serving.
    #[test]
    fn the_older_participant_serves_on_and_the_newcomer_refuses_whatever_the_gap() {
        let older = participant("aa", Some(1_000_000));
        let newcomer = participant("bb", Some(1_006_000));
        for since_start in [Duration::ZERO, Duration::from_secs(7), STARTUP_WINDOW * 10] {
            let seen_by_older = [Rival {
                participant: newcomer.clone(),
                claims: vec!["serves /cstep/evaluate".into()],
            }];
            let seen_by_newcomer = [Rival {
                participant: older.clone(),
                claims: vec!["serves /cstep/evaluate".into()],
            }];
            assert!(matches!(
                verdict(&seen_by_older, &older, since_start, "/n", 7),
                Verdict::Warn(_)
            ));
            let Verdict::Refuse(line) = verdict(&seen_by_newcomer, &newcomer, since_start, "/n", 7)
            else {
                panic!("the newcomer refuses at {since_start:?}");
            };
            assert!(line.contains("participant aa"), "{line}");
        }
        // The same millisecond: the prefixes decide, the same way on both sides.
        let (a, b) = (participant("aa", Some(5)), participant("bb", Some(5)));
        let sees = |p: &Participant| [rival(&p.id, p.created_ms)];
        assert!(matches!(
            verdict(&sees(&b), &a, Duration::ZERO, "/n", 7),
            Verdict::Warn(_)
        ));
        assert!(matches!(
            verdict(&sees(&a), &b, Duration::ZERO, "/n", 7),
            Verdict::Refuse(_)
        ));
        // A time decades away is an unpatched RustDDS's random bytes: its age is unknown.
        let far = participant("cc", Some(1_000_000 + 40 * PLAUSIBLE_AGE_GAP_MS));
        let own = participant("own", Some(1_000_000));
        assert!(matches!(
            verdict(&sees(&far), &own, STARTUP_WINDOW, "/n", 7),
            Verdict::Warn(_)
        ));
        assert!(matches!(
            verdict(&sees(&far), &own, Duration::ZERO, "/n", 7),
            Verdict::Refuse(_)
        ));
    }
}
