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

use crate::ros::messages::{ros_type_of_dds, RosMessage, RosService};

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
/// use it), each with the type this node writes there.
#[derive(Debug, Clone, Default)]
pub struct Claims {
    claims: Vec<Claim>,
}

/// One DDS topic this node alone should write.
#[derive(Debug, Clone)]
struct Claim {
    /// The DDS topic, `rt/<topic>` or `rr/<service>Reply`.
    dds_topic: String,
    /// The DDS type this node writes there.
    dds_type: String,
    /// The topic's or service's ROS name.
    ros_name: String,
    /// Its ROS type, as ROS tools print it.
    ros_type: String,
    /// What the node does there, in ROS terms, for messages ("publishes /cstep/empowerment").
    what: String,
}

/// A writer or reader of another participant, as DDS discovery reports it.
#[derive(Debug, Clone)]
pub struct Endpoint<'a> {
    /// Its DDS topic name.
    pub topic: &'a str,
    /// Its DDS type name.
    pub type_name: &'a str,
    /// Its participant.
    pub participant: Participant,
}

impl Claims {
    /// No claims yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Claims the absolute ROS topic `name` (this node publishes `M` there).
    pub fn topic<M: RosMessage>(mut self, name: &str) -> Self {
        self.claims.push(Claim {
            dds_topic: format!("rt{name}"),
            dds_type: M::dds_type(),
            ros_name: name.to_owned(),
            ros_type: M::ros_type(),
            what: format!("publishes {name}"),
        });
        self
    }

    /// Claims the absolute ROS service `name` (this node serves `S` there): its reply topic.
    pub fn service<S: RosService>(mut self, name: &str) -> Self {
        self.claims.push(Claim {
            dds_topic: format!("rr{name}Reply"),
            dds_type: S::dds_response_type(),
            ros_name: name.to_owned(),
            ros_type: S::ros_type(),
            what: format!("serves {name}"),
        });
        self
    }

    /// The rivals among discovered `writers`: writers of the type this node writes on a topic
    /// it claims; `own` is this node's participant, whose writers are not rivals. One [`Rival`]
    /// per participant, naming every claim it infringes, in order.
    pub fn rivals<'a>(
        &self,
        writers: impl IntoIterator<Item = Endpoint<'a>>,
        own: &Participant,
    ) -> Vec<Rival> {
        let mut found: Vec<Rival> = Vec::new();
        let mut seen = BTreeSet::new();
        for writer in writers {
            if writer.participant.id == own.id {
                continue;
            }
            let Some(claim) = self
                .claims
                .iter()
                .find(|c| c.dds_topic == writer.topic && c.dds_type == writer.type_name)
            else {
                continue;
            };
            if !seen.insert((writer.participant.id.clone(), claim.what.clone())) {
                continue;
            }
            match found
                .iter_mut()
                .find(|r| r.participant == writer.participant)
            {
                Some(rival) => rival.claims.push(claim.what.clone()),
                None => found.push(Rival {
                    participant: writer.participant,
                    claims: vec![claim.what.clone()],
                }),
            }
        }
        for rival in &mut found {
            rival.claims.sort_by_key(|what| {
                self.claims
                    .iter()
                    .position(|c| &c.what == what)
                    .unwrap_or(usize::MAX)
            });
        }
        found
    }

    /// The claimed topics that other participants' `endpoints` (writers and readers) use with
    /// another type — an output remapped onto a topic in use, say `/rosout`: DDS matches
    /// nobody across the two types, so neither side hears the other. One line per claim and
    /// foreign type, in the claims' order.
    pub fn clashes<'a>(
        &self,
        endpoints: impl IntoIterator<Item = Endpoint<'a>>,
        own: &Participant,
    ) -> Vec<String> {
        let mut found: Vec<(usize, String, String)> = Vec::new();
        for endpoint in endpoints {
            if endpoint.participant.id == own.id {
                continue;
            }
            let Some(index) = self
                .claims
                .iter()
                .position(|c| c.dds_topic == endpoint.topic && c.dds_type != endpoint.type_name)
            else {
                continue;
            };
            if !found
                .iter()
                .any(|(i, theirs, _)| *i == index && theirs == endpoint.type_name)
            {
                found.push((
                    index,
                    endpoint.type_name.to_owned(),
                    endpoint.participant.id.clone(),
                ));
            }
        }
        found.sort_by_key(|(index, _, _)| *index);
        found
            .into_iter()
            .map(|(index, theirs, participant)| {
                let claim = &self.claims[index];
                let theirs = ros_type_of_dds(&theirs)
                    .map(|t| t.strip_suffix("_Response").map_or(t.clone(), str::to_owned))
                    .unwrap_or(theirs);
                format!(
                    "{} is in use as {theirs} (participant {participant}, and perhaps others), \
                     but this node {} as {}: the two types never match, so neither side hears \
                     the other (check the remapping)",
                    claim.ros_name, claim.what, claim.ros_type
                )
            })
            .collect()
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
    use crate::ros::messages::{EmpoweredReward, Empowerment, Evaluate, EvaluateBatch};

    fn claims() -> Claims {
        Claims::new()
            .topic::<Empowerment>("/cstep/empowerment")
            .topic::<EmpoweredReward>("/cstep/reward")
            .service::<Evaluate>("/cstep/evaluate")
            .service::<EvaluateBatch>("/cstep/evaluate_batch")
    }

    /// Endpoints from (DDS topic, DDS type, participant id).
    fn endpoints<'a>(
        list: &'a [(&'a str, &'a str, &'a str)],
    ) -> impl Iterator<Item = Endpoint<'a>> + 'a {
        list.iter().map(|(topic, type_name, id)| Endpoint {
            topic,
            type_name,
            participant: participant(id, None),
        })
    }

    const EMPOWERMENT: &str = "cstep_msgs::msg::dds_::Empowerment_";
    const REWARD: &str = "cstep_msgs::msg::dds_::EmpoweredReward_";
    const EVALUATE_REPLY: &str = "cstep_msgs::srv::dds_::Evaluate_Response_";

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
            ("rt/cstep/empowerment", EMPOWERMENT, "aa"),
            ("rr/cstep/evaluateReply", EVALUATE_REPLY, "bb"),
            ("rt/cstep/reward", REWARD, "bb"),
            ("rr/cstep/evaluateReply", EVALUATE_REPLY, "bb"), // a second server in one participant
            ("rt/cstep/empowerment", EMPOWERMENT, "own"),
            (
                "rt/diagnostics",
                "diagnostic_msgs::msg::dds_::DiagnosticArray_",
                "cc",
            ),
            (
                "rq/cstep/evaluateRequest",
                "cstep_msgs::srv::dds_::Evaluate_Request_",
                "dd",
            ),
            ("rt/cstep/empowerment_other", EMPOWERMENT, "ee"),
            ("rt/cstep/reward", "std_msgs::msg::dds_::Float64_", "ff"), // another type
        ];
        let rivals = claims().rivals(endpoints(&writers), &participant("own", None));
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

    /// `-r cstep/empowerment:=/rosout`: before the type was compared, every node's `/rosout`
    /// writer read as a rival publishing the node's scores, and the node quit blaming them.
    #[test]
    fn a_claimed_topic_in_use_with_another_type_is_a_clash_not_a_rival() {
        let claims = Claims::new()
            .topic::<Empowerment>("/rosout")
            .service::<Evaluate>("/cstep/evaluate");
        let graph = [
            ("rt/rosout", "rcl_interfaces::msg::dds_::Log_", "aa"),
            ("rt/rosout", "rcl_interfaces::msg::dds_::Log_", "bb"),
            ("rt/rosout", EMPOWERMENT, "own"),
            (
                "rr/cstep/evaluateReply",
                "example_interfaces::srv::dds_::AddTwoInts_Response_",
                "cc",
            ),
            ("rr/cstep/evaluateReply", EVALUATE_REPLY, "dd"),
            ("rt/cstep/other", "std_msgs::msg::dds_::String_", "ee"),
        ];
        let own = participant("own", None);
        let rivals = claims.rivals(endpoints(&graph), &own);
        assert_eq!(rivals.len(), 1, "{rivals:?}");
        assert_eq!(
            rivals[0].describe(),
            "participant dd also serves /cstep/evaluate"
        );
        let clashes = claims.clashes(endpoints(&graph), &own);
        assert_eq!(clashes.len(), 2, "{clashes:?}");
        for (line, parts) in clashes.iter().zip([
            [
                "/rosout is in use as rcl_interfaces/msg/Log (participant aa",
                "this node publishes /rosout as cstep_msgs/msg/Empowerment",
            ],
            [
                "/cstep/evaluate is in use as example_interfaces/srv/AddTwoInts (participant cc",
                "serves /cstep/evaluate as cstep_msgs/srv/Evaluate",
            ],
        ]) {
            assert!(!line.contains('\n'), "{line}");
            for part in parts {
                assert!(line.contains(part), "{part}: {line}");
            }
        }
        assert!(claims.clashes(endpoints(&graph[2..3]), &own).is_empty());
    }
}
