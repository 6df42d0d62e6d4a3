//! Adversarial parameters files: whatever a file under the input cap holds, it is read or refused
//! within [`CASE_BOUND`], with a one-line error no longer than [`MAX_ERROR_BYTES`].
//!
//! Before `cstep::parameters::yaml` a file of 200 000 nested `[` (200 KB) took minutes to be refused,
//! and files of many sections, or of many parameters in one section, took time in the square
//! of their size (a 15 MiB file 470 s); `%TAG` directives did too, and ten anchors of ten aliases
//! each expand to 10¹⁰ values. The cases are drawn by proptest from recipes of those shapes —
//! deep nesting (flow and block), many sections, many parameters, anchors and aliases, long
//! scalars, long keys, many directives — each sized from a few bytes up to the cap, and read as
//! the node and `cstep eval --config` read a parameters file ([`load_all`]). The bound is
//! generous: it catches a quadratic or exponential cost, which took minutes, not a slow machine.
//!
//! `cargo test` runs [`DEFAULT_CASES`] cases. The long run (`make fuzz-yaml`):
//!
//! ```sh
//! YAML_FUZZ_CASES=2000 YAML_FUZZ_SEED=1 cargo test --test yaml_fuzz -- --nocapture
//! ```

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use cstep::input::file::MAX_INPUT_FILE_BYTES;
use cstep::parameters::{load_all, DEFAULT_NODE_NAME};
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

/// Cases when `YAML_FUZZ_CASES` is unset.
const DEFAULT_CASES: u64 = 24;

/// The run's seed when `YAML_FUZZ_SEED` is unset.
const DEFAULT_SEED: u64 = 45;

/// The most a case may take to be read or refused.
const CASE_BOUND: Duration = Duration::from_secs(5);

/// The longest error accepted: the longest the loader writes is an unknown parameter's, which
/// lists every known name; values and names in errors are excerpts.
const MAX_ERROR_BYTES: usize = 1024;

/// The most a generated text may hold: the input cap, less room for the section before it.
const ROOM: usize = MAX_INPUT_FILE_BYTES as usize - 1024;

/// The section every case starts with, so that a file whose rest is harmless loads.
const OWN_SECTION: &str = "cstep_node:\n  ros__parameters:\n    horizon: 0.5\n";

/// How to build one adversarial file (small, so proptest prints it, not the text).
#[derive(Debug, Clone)]
enum Recipe {
    /// `depth` nested flow sequences or mappings (`[`, `{`, or both by turns), closed or not.
    FlowNesting {
        depth: usize,
        open: &'static str,
        closed: bool,
    },
    /// `depth` nested block sequences (`- - - x`) or block mappings (indented by one more each).
    BlockNesting { depth: usize, mappings: bool },
    /// `sections` sections for other nodes, of `parameters` parameters each.
    Sections { sections: usize, parameters: usize },
    /// One other node's section of `parameters` parameters, in flow style or block style.
    Parameters { parameters: usize, flow: bool },
    /// `levels` anchors, each a sequence of `fanout` aliases of the one before; the first holds
    /// a scalar of `scalar` bytes ("billion laughs").
    Aliases {
        levels: usize,
        fanout: usize,
        scalar: usize,
    },
    /// One scalar of `bytes` bytes, as the key or the value of a parameter, in `style`.
    LongScalar {
        bytes: usize,
        key: bool,
        style: &'static str,
    },
    /// Keys nested `depth` deep of `bytes` bytes each, with `leaves` parameters under them.
    LongKeys {
        depth: usize,
        bytes: usize,
        leaves: usize,
    },
    /// `count` `%TAG` directives before the document.
    Directives { count: usize },
}

impl Recipe {
    /// The file's text: [`OWN_SECTION`], then what the recipe says, cut to the input cap.
    fn text(&self) -> String {
        let mut text = String::new();
        match *self {
            Recipe::FlowNesting {
                depth,
                open,
                closed,
            } => {
                // At most five bytes a level (`{a: ` and `}`).
                let depth = depth.min(ROOM / 5);
                text += OWN_SECTION;
                text += "    nested: ";
                let mut closes = Vec::with_capacity(depth);
                for level in 0..depth {
                    let bracket = open.as_bytes()[level % open.len()];
                    let (o, c) = if bracket == b'[' {
                        ("[", "]")
                    } else {
                        ("{a: ", "}")
                    };
                    text += o;
                    closes.push(c);
                }
                if closed {
                    text.extend(closes.iter().rev().copied());
                }
                text += "\n";
            }
            Recipe::BlockNesting { depth, mappings } => {
                text += OWN_SECTION;
                if mappings {
                    // Line `i` is indented by `i`: the text grows in the square of the depth.
                    let depth = depth.min(((2 * ROOM) as f64).sqrt() as usize / 2);
                    text += "other:\n  ros__parameters:\n";
                    for level in 0..depth {
                        writeln!(text, "{:1$}a:", "", 4 + level).unwrap();
                    }
                    writeln!(text, "{:1$}x", "", 4 + depth).unwrap();
                } else {
                    text += "    nested: ";
                    text += &"- ".repeat(depth.min(ROOM / 2));
                    text += "x\n";
                }
            }
            Recipe::Sections {
                sections,
                parameters,
            } => {
                text += OWN_SECTION;
                for s in 0..sections {
                    if text.len() > ROOM - 64 * (parameters + 1) {
                        break;
                    }
                    writeln!(text, "/ns{}/other_node_{s}:\n  ros__parameters:", s % 7).unwrap();
                    for p in 0..parameters {
                        writeln!(text, "    p{p}: {s}").unwrap();
                    }
                }
            }
            Recipe::Parameters { parameters, flow } => {
                text += OWN_SECTION;
                text += "other:\n  ros__parameters:";
                text += if flow { " {" } else { "\n" };
                for p in 0..parameters {
                    if text.len() > ROOM - 64 {
                        break;
                    }
                    if flow {
                        write!(text, "p{p}: {p}, ").unwrap();
                    } else {
                        writeln!(text, "    p{p}: {p}").unwrap();
                    }
                }
                text += if flow { "last: 0}\n" } else { "" };
            }
            Recipe::Aliases {
                levels,
                fanout,
                scalar,
            } => {
                writeln!(text, "a0: &a0 {}", "x".repeat(scalar.min(ROOM / 2))).unwrap();
                for level in 1..levels {
                    let aliases = vec![format!("*a{}", level - 1); fanout].join(", ");
                    writeln!(text, "a{level}: &a{level} [{aliases}]").unwrap();
                }
                text += OWN_SECTION;
                writeln!(text, "    laughs: *a{}", levels - 1).unwrap();
            }
            Recipe::LongScalar { bytes, key, style } => {
                let bytes = bytes.min(ROOM - 64);
                let scalar = match style {
                    "'" | "\"" => format!("{style}{}{style}", "x".repeat(bytes)),
                    "|" => format!("|\n      {}\n", "x y".repeat(bytes / 3)),
                    _ => "x".repeat(bytes),
                };
                text += OWN_SECTION;
                if key {
                    writeln!(text, "    ? {scalar}\n    : 1").unwrap();
                } else {
                    writeln!(text, "    sampler: {scalar}").unwrap();
                }
            }
            Recipe::LongKeys {
                depth,
                bytes,
                leaves,
            } => {
                text += OWN_SECTION;
                text += "other:\n  ros__parameters:\n    ";
                for level in 0..depth {
                    write!(text, "{}{level}: {{", "k".repeat(bytes.min(ROOM / depth))).unwrap();
                }
                for leaf in 0..leaves {
                    if text.len() > ROOM - 16 - depth {
                        break;
                    }
                    write!(text, "p{leaf}: 1, ").unwrap();
                }
                text += "last: 0";
                text += &"}".repeat(depth);
                text += "\n";
            }
            Recipe::Directives { count } => {
                for t in 0..count.min(ROOM / 48) {
                    writeln!(text, "%TAG !t{t}! tag:example.com,2000:").unwrap();
                }
                text += "---\n";
                text += OWN_SECTION;
            }
        }
        text
    }
}

/// A size from 1 to `max`, log-uniform: as many cases of a few bytes as of megabytes.
fn size(max: usize) -> impl Strategy<Value = usize> {
    (0.0..(max as f64).ln()).prop_map(|ln| ln.exp() as usize)
}

/// Every recipe, sized up to the input cap.
fn recipes() -> impl Strategy<Value = Recipe> {
    prop_oneof![
        (
            size(ROOM),
            prop::sample::select(vec!["[", "{", "[{"]),
            any::<bool>()
        )
            .prop_map(|(depth, open, closed)| Recipe::FlowNesting {
                depth,
                open,
                closed
            }),
        (size(ROOM), any::<bool>())
            .prop_map(|(depth, mappings)| Recipe::BlockNesting { depth, mappings }),
        (size(ROOM), 1..5_usize).prop_map(|(sections, parameters)| Recipe::Sections {
            sections,
            parameters
        }),
        (size(ROOM), any::<bool>())
            .prop_map(|(parameters, flow)| Recipe::Parameters { parameters, flow }),
        (1..40_usize, 1..16_usize, size(ROOM)).prop_map(|(levels, fanout, scalar)| {
            Recipe::Aliases {
                levels,
                fanout,
                scalar,
            }
        }),
        (
            size(ROOM),
            any::<bool>(),
            prop::sample::select(vec!["", "'", "\"", "|"])
        )
            .prop_map(|(bytes, key, style)| Recipe::LongScalar { bytes, key, style }),
        (1..80_usize, size(4096), size(ROOM)).prop_map(|(depth, bytes, leaves)| {
            Recipe::LongKeys {
                depth,
                bytes,
                leaves,
            }
        }),
        size(ROOM).prop_map(|count| Recipe::Directives { count }),
    ]
}

/// A number from the environment variable `name`, or `default` when it is unset.
fn env_number(name: &str, default: u64) -> u64 {
    std::env::var(name).map_or(default, |v| {
        v.parse()
            .unwrap_or_else(|_| panic!("{name}={v:?} is not a number"))
    })
}

/// A scratch directory of this test's own.
fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cstep-yaml-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes the recipe's text to `path` and reads it as the node does, asserting that it took
/// less than [`CASE_BOUND`] and that an error is one short line; the text's size, how long it
/// took and what came of it ("read", or the error). `case` names the case in a failure.
fn read_within_bound(path: &Path, recipe: &Recipe, case: &str) -> (usize, Duration, String) {
    let text = recipe.text();
    assert!(
        text.len() as u64 <= MAX_INPUT_FILE_BYTES,
        "{case}: {recipe:?}"
    );
    std::fs::write(path, &text).unwrap();
    let started = Instant::now();
    let result = load_all(&[path], DEFAULT_NODE_NAME, &[]);
    let took = started.elapsed();
    let bytes = text.len();
    assert!(
        took < CASE_BOUND,
        "{case}: {recipe:?}: {bytes} bytes took {took:?}"
    );
    let outcome = match result {
        Ok(_) => "read".to_owned(),
        Err(e) => e.to_string(),
    };
    assert_eq!(outcome.lines().count(), 1, "{case}: {recipe:?}: {outcome}");
    assert!(
        outcome.len() <= MAX_ERROR_BYTES,
        "{case}: {recipe:?}: a {}-byte error: {outcome:.300}",
        outcome.len()
    );
    (bytes, took, outcome)
}

#[test]
fn every_file_under_the_cap_is_read_or_refused_within_seconds() {
    let cases = env_number("YAML_FUZZ_CASES", DEFAULT_CASES);
    let seed = env_number("YAML_FUZZ_SEED", DEFAULT_SEED);
    let mut seed_bytes = [0; 32];
    seed_bytes[..8].copy_from_slice(&seed.to_le_bytes());
    // Cases are drawn, not shrunk: a failure prints its recipe, and shrinking would rebuild
    // megabyte files many times over.
    let mut runner = TestRunner::new_with_rng(
        Config::default(),
        TestRng::from_seed(RngAlgorithm::ChaCha, &seed_bytes),
    );
    let strategy = recipes();
    let path = scratch().join("case.yaml");
    let started = Instant::now();
    let (mut bytes, mut slowest) = (0_usize, (Duration::ZERO, 0_usize));
    let (mut read, mut refused) = (0_u64, 0_u64);
    for case in 0..cases {
        let recipe = strategy.new_tree(&mut runner).unwrap().current();
        let name = format!("YAML_FUZZ_SEED={seed}, case {case}");
        let (size, took, outcome) = read_within_bound(&path, &recipe, &name);
        bytes += size;
        slowest = slowest.max((took, size));
        if outcome == "read" {
            read += 1;
        } else {
            refused += 1;
        }
    }
    println!(
        "YAML fuzz: {cases} cases, seed {seed}, {:.1} MB in {:.1} s: {read} read, {refused} \
         refused; slowest {:.2} s ({} bytes)",
        bytes as f64 / 1e6,
        started.elapsed().as_secs_f64(),
        slowest.0.as_secs_f64(),
        slowest.1
    );
}

#[test]
fn the_files_that_stalled_the_node_are_read_or_refused_within_seconds() {
    // Measured before: 200 000 nested `[` took 45–74 s to be refused; other nodes'
    // sections 5.7 s at 2.7 MB and 470 s at 15 MiB; and the shapes that cost the same way.
    let path = scratch().join("reported.yaml");
    let cases = [
        (
            Recipe::FlowNesting {
                depth: 200_000,
                open: "[",
                closed: false,
            },
            "values nested more than 64 levels deep",
        ),
        (
            Recipe::Sections {
                sections: 12_000,
                parameters: 2,
            },
            "read",
        ),
        (
            Recipe::Sections {
                sections: 400_000,
                parameters: 2,
            },
            "more than 100000 values",
        ),
        (
            Recipe::Parameters {
                parameters: 49_000,
                flow: false,
            },
            "read",
        ),
        (
            Recipe::Aliases {
                levels: 10,
                fanout: 10,
                scalar: 1,
            },
            "more than 100000 values",
        ),
        (
            Recipe::Aliases {
                levels: 3,
                fanout: 10,
                scalar: 1 << 20,
            },
            "aliases expanding to more than 16 MiB of text",
        ),
        (
            Recipe::Directives { count: 100_000 },
            "more than 16 % directives",
        ),
        (
            Recipe::LongScalar {
                bytes: 15 << 20,
                key: false,
                style: "\"",
            },
            "'sampler' must be one of bang_bang | fourier | chebyshev, got \"xxxx",
        ),
    ];
    for (recipe, expected) in cases {
        let (_, took, outcome) = read_within_bound(&path, &recipe, "reported");
        assert!(outcome.contains(expected), "{recipe:?}: {outcome}");
        println!("{recipe:?}: {took:?}, {outcome:.120}");
    }
}

#[test]
fn sigterm_stops_the_node_while_it_reads_its_parameters_file() {
    // Once the node ignored SIGTERM for up to 440 s while it parsed a parameters file. The
    // file here is the largest shape it reads (one section of 49 000 parameters, which before
    // took seconds in the square of its size); the signal comes while it is being read.
    let path = scratch().join("sigterm.yaml");
    let recipe = Recipe::Parameters {
        parameters: 49_000,
        flow: false,
    };
    std::fs::write(&path, recipe.text()).unwrap();
    let mut node = std::process::Command::new(env!("CARGO_BIN_EXE_cstep"))
        .args(["node", "--ros-args", "--params-file"])
        .arg(&path)
        // Private and local, should it get as far as joining a domain.
        .env("ROS_DOMAIN_ID", "229")
        .env("ROS_AUTOMATIC_DISCOVERY_RANGE", "OFF")
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("cstep runs");
    std::thread::sleep(Duration::from_millis(50));
    let signalled = Instant::now();
    let kill = std::process::Command::new("kill")
        .args(["-TERM", &node.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let status = loop {
        if let Some(status) = node.try_wait().unwrap() {
            break status;
        }
        if signalled.elapsed() > CASE_BOUND {
            node.kill().unwrap();
            panic!("still running {CASE_BOUND:?} after SIGTERM");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    // A clean stop, or — had the signal come before the handler was installed — its default.
    use std::os::unix::process::ExitStatusExt;
    assert!(
        status.success() || status.signal() == Some(15),
        "{status:?}"
    );
}
