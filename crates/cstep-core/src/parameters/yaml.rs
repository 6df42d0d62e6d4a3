//! Reading YAML that a user gave (a parameters file, a `-p` value) at a cost its size says.
//!
//! `serde_norway` hands the whole text to libyaml and builds the value only once every event of
//! the document is in memory, and libyaml itself is not linear on every input: each token costs
//! as many steps as the flow collections (`[`, `{`) it sits in, so 200 000 nested `[` (a
//! 200 KB file) would take minutes to be refused; and each `%TAG` directive is compared with every
//! earlier one. Aliases multiply: ten anchors of ten aliases each expand to 10¹⁰ values (the
//! "billion laughs"). And a value nested under long keys becomes a long dotted name, once per
//! value beneath them.
//!
//! [`from_str`] therefore reads the text twice. First a pre-scan: a count of `%` directives, then
//! libyaml's events one at a time, stopping at the first that breaks one of the limits below —
//! so libyaml never works deeper than [`MAX_DEPTH`] levels, and the pre-scan costs time linear in
//! the text and memory linear in its anchors. Only a text within every limit goes on to
//! `serde_norway`, whose work is then bounded by the same limits. A refusal is one line naming
//! the limit and where in the text it was passed.

use std::collections::HashMap;
use std::ffi::CStr;
use std::fmt;
use std::marker::PhantomData;
use std::mem::MaybeUninit;

use serde_norway::Value;
use unsafe_libyaml_norway as unsafe_libyaml;

/// The deepest a value may nest (sequences and mappings within one another). A parameters file
/// nests node namespaces, `ros__parameters` and dotted parameter names: a handful of levels.
pub const MAX_DEPTH: usize = 64;

/// The most values (scalars, sequences and mappings, aliases counted as what they stand for) a
/// document may hold: parameters files hold hundreds.
pub const MAX_VALUES: u64 = 100_000;

/// The most bytes of scalar text a document may expand to (aliases counted as the text they
/// stand for): a text without aliases never holds more than the input file cap.
pub const MAX_EXPANDED_BYTES: u64 = crate::input::file::MAX_INPUT_FILE_BYTES;

/// The most bytes the keys leading to a value may have together, plus one per key (a
/// parameter's dotted name and the node section it is in; a ROS node's name is at most 255
/// characters). Every value under a key gets a name this long.
pub const MAX_KEY_PATH_BYTES: usize = 512;

/// The most `%YAML` and `%TAG` directives a text may have (parameters files have none).
pub const MAX_DIRECTIVES: usize = 16;

/// Why a YAML text was not read.
#[derive(Debug, thiserror::Error)]
pub enum YamlError {
    /// The text is not YAML (`serde_norway`'s reason).
    #[error("not valid YAML: {0}")]
    Syntax(#[from] serde_norway::Error),
    /// The text passed one of this module's limits.
    #[error("refused before reading: {0}")]
    Limit(#[from] LimitError),
}

/// A limit a YAML text passed, and where.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{limit} (at line {line} column {column})")]
pub struct LimitError {
    /// Which limit.
    pub limit: Limit,
    /// The line (from 1) of the value that passed it.
    pub line: u64,
    /// Its column (from 1).
    pub column: u64,
}

/// The limits [`from_str`] enforces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Limit {
    /// Nested deeper than [`MAX_DEPTH`].
    Depth,
    /// More than [`MAX_VALUES`] values.
    Values,
    /// More than [`MAX_EXPANDED_BYTES`] of text once aliases are expanded.
    ExpandedBytes,
    /// A key path longer than [`MAX_KEY_PATH_BYTES`].
    KeyPath,
    /// A key that is a sequence or a mapping (parameter and node names are scalars).
    CollectionKey,
    /// More than [`MAX_DIRECTIVES`] directives.
    Directives,
}

impl fmt::Display for Limit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Limit::Depth => write!(f, "values nested more than {MAX_DEPTH} levels deep"),
            Limit::Values => write!(f, "more than {MAX_VALUES} values"),
            Limit::ExpandedBytes => write!(
                f,
                "aliases expanding to more than {} MiB of text",
                MAX_EXPANDED_BYTES >> 20
            ),
            Limit::KeyPath => write!(
                f,
                "keys leading to a value longer than {MAX_KEY_PATH_BYTES} bytes together"
            ),
            Limit::CollectionKey => {
                f.write_str("a key that is a sequence or a mapping (keys must be scalars)")
            }
            Limit::Directives => write!(f, "more than {MAX_DIRECTIVES} % directives"),
        }
    }
}

/// Reads one YAML document into a value, refusing up front a text beyond the module's limits.
pub fn from_str(text: &str) -> Result<Value, YamlError> {
    prescan(text)?;
    Ok(serde_norway::from_str(text)?)
}

/// Checks `text` against every limit, in one pass over it and its events. A syntax error ends
/// the pre-scan without an error: the full parse, bounded by the limits held up to that point,
/// reports it.
fn prescan(text: &str) -> Result<(), LimitError> {
    count_directives(text)?;
    let mut parser = Parser::new(text);
    let mut budget = Budget::default();
    while let Some((event, mark)) = parser.next() {
        budget.take(event).map_err(|limit| LimitError {
            limit,
            line: mark.line + 1,
            column: mark.column + 1,
        })?;
    }
    Ok(())
}

/// Refuses more than [`MAX_DIRECTIVES`] lines starting with `%`: libyaml reads every directive
/// of a document in one step, comparing each with all before it, so they are counted in the
/// text. (A `%` opening a line inside a document is no directive, but no YAML reader takes it
/// for anything else either: libyaml refuses it.)
fn count_directives(text: &str) -> Result<(), LimitError> {
    let starts = std::iter::once(0).chain(text.match_indices('\n').map(|(at, _)| at + 1));
    let mut directives = starts
        .enumerate()
        .filter(|(_, at)| text[*at..].starts_with('%'));
    match directives.nth(MAX_DIRECTIVES) {
        None => Ok(()),
        Some((line, _)) => Err(LimitError {
            limit: Limit::Directives,
            line: line as u64 + 1,
            column: 1,
        }),
    }
}

/// One libyaml event, as far as the limits care.
enum Event {
    /// A scalar of `len` bytes.
    Scalar { anchor: Option<Box<[u8]>>, len: u64 },
    /// A sequence (`mapping: false`) or mapping starts.
    Start {
        anchor: Option<Box<[u8]>>,
        mapping: bool,
    },
    /// The innermost open sequence or mapping ends.
    End,
    /// An alias of the node anchored as `anchor`.
    Alias { anchor: Box<[u8]> },
    /// Stream and document boundaries.
    Boundary,
}

/// An open sequence or mapping.
struct Frame {
    /// Whether it is a mapping.
    mapping: bool,
    /// In a mapping: whether the next node is a key.
    expect_key: bool,
    /// In a mapping: the bytes its current key adds to the key path (0 between entries).
    key_bytes: usize,
    /// Its anchor, with the values and bytes counted before it started.
    anchor: Option<(Box<[u8]>, u64, u64)>,
}

/// What the events read so far cost, against the limits.
#[derive(Default)]
struct Budget {
    /// The open collections, outermost first.
    open: Vec<Frame>,
    /// Values so far, aliases expanded.
    values: u64,
    /// Scalar bytes so far, aliases expanded.
    bytes: u64,
    /// The bytes of the keys leading to the current node.
    key_path: usize,
    /// Each anchor's expanded values and bytes (a later anchor of the same name replaces it).
    anchors: HashMap<Box<[u8]>, (u64, u64)>,
}

impl Budget {
    /// Counts one event; the limit it passes, if any.
    fn take(&mut self, event: Event) -> Result<(), Limit> {
        match event {
            Event::Boundary => Ok(()),
            Event::Scalar { anchor, len } => {
                self.key(Some(len))?;
                self.add(1, len)?;
                if let Some(name) = anchor {
                    self.anchors.insert(name, (1, len));
                }
                self.done();
                Ok(())
            }
            Event::Alias { anchor } => {
                let (values, bytes) = self.anchors.get(&anchor).copied().unwrap_or((1, 0));
                // A key standing for a scalar is as long as that scalar; for more, refused.
                self.key((values == 1).then_some(bytes))?;
                self.add(values, bytes)?;
                self.done();
                Ok(())
            }
            Event::Start { anchor, mapping } => {
                self.key(None)?;
                if self.open.len() >= MAX_DEPTH {
                    return Err(Limit::Depth);
                }
                self.add(1, 0)?;
                let anchor = anchor.map(|name| (name, self.values - 1, self.bytes));
                self.open.push(Frame {
                    mapping,
                    expect_key: mapping,
                    key_bytes: 0,
                    anchor,
                });
                Ok(())
            }
            Event::End => {
                if let Some(frame) = self.open.pop() {
                    if let Some((name, values, bytes)) = frame.anchor {
                        self.anchors
                            .insert(name, (self.values - values, self.bytes - bytes));
                    }
                    self.done();
                }
                Ok(())
            }
        }
    }

    /// Adds a node of `values` values and `bytes` bytes, within the limits.
    fn add(&mut self, values: u64, bytes: u64) -> Result<(), Limit> {
        self.values = self.values.saturating_add(values);
        self.bytes = self.bytes.saturating_add(bytes);
        if self.values > MAX_VALUES {
            return Err(Limit::Values);
        }
        if self.bytes > MAX_EXPANDED_BYTES {
            return Err(Limit::ExpandedBytes);
        }
        Ok(())
    }

    /// If the node starting now is a mapping's key — a scalar of `len` bytes, or a collection
    /// (`None`) — adds it to the key path, within the limits.
    fn key(&mut self, len: Option<u64>) -> Result<(), Limit> {
        let Some(frame) = self.open.last_mut().filter(|f| f.mapping && f.expect_key) else {
            return Ok(());
        };
        let len = len.ok_or(Limit::CollectionKey)?;
        // One byte more for the separator in a dotted name.
        let bytes = usize::try_from(len).unwrap_or(usize::MAX).saturating_add(1);
        frame.key_bytes = bytes;
        self.key_path = self.key_path.saturating_add(bytes);
        if self.key_path > MAX_KEY_PATH_BYTES {
            return Err(Limit::KeyPath);
        }
        Ok(())
    }

    /// A node ended: in a mapping, a key's value follows it, or a value's key ends.
    fn done(&mut self) {
        if let Some(frame) = self.open.last_mut().filter(|f| f.mapping) {
            frame.expect_key = !frame.expect_key;
            if frame.expect_key {
                self.key_path -= frame.key_bytes;
                frame.key_bytes = 0;
            }
        }
    }
}

/// libyaml's event parser over a borrowed text (as `serde_norway` drives it, one event at a
/// time): its state lives in a box, at an address that never changes.
struct Parser<'text> {
    state: Box<MaybeUninit<unsafe_libyaml::yaml_parser_t>>,
    done: bool,
    text: PhantomData<&'text str>,
}

impl<'text> Parser<'text> {
    fn new(text: &'text str) -> Self {
        let mut state = Box::new(MaybeUninit::<unsafe_libyaml::yaml_parser_t>::uninit());
        // SAFETY: libyaml initializes the parser in place (it only fails to allocate, which
        // aborts as any failed allocation does), then reads `text`, which outlives the parser
        // ('text), from its pointer; the box keeps the parser at one address until `drop`.
        unsafe {
            let parser = state.as_mut_ptr();
            assert!(
                !unsafe_libyaml::yaml_parser_initialize(parser).fail,
                "libyaml could not allocate its parser"
            );
            unsafe_libyaml::yaml_parser_set_encoding(parser, unsafe_libyaml::YAML_UTF8_ENCODING);
            unsafe_libyaml::yaml_parser_set_input_string(parser, text.as_ptr(), text.len() as _);
        }
        Self {
            state,
            done: false,
            text: PhantomData,
        }
    }

    /// The next event and where it starts; `None` after the stream's end or a syntax error.
    fn next(&mut self) -> Option<(Event, unsafe_libyaml::yaml_mark_t)> {
        if self.done {
            return None;
        }
        let mut raw = MaybeUninit::<unsafe_libyaml::yaml_event_t>::uninit();
        // SAFETY: the parser was initialized in `new`; a successful `yaml_parser_parse` fills
        // the event, whose union member is the one its type names, and whose anchor strings
        // are NUL-terminated; the event is read, then freed once.
        unsafe {
            let parser = self.state.as_mut_ptr();
            if unsafe_libyaml::yaml_parser_parse(parser, raw.as_mut_ptr()).fail {
                self.done = true;
                return None;
            }
            let raw = raw.assume_init_mut();
            let anchor = |name: *const u8| {
                (!name.is_null()).then(|| Box::from(CStr::from_ptr(name.cast()).to_bytes()))
            };
            let event = match raw.type_ {
                unsafe_libyaml::YAML_SCALAR_EVENT => Event::Scalar {
                    anchor: anchor(raw.data.scalar.anchor),
                    len: raw.data.scalar.length,
                },
                unsafe_libyaml::YAML_SEQUENCE_START_EVENT => Event::Start {
                    anchor: anchor(raw.data.sequence_start.anchor),
                    mapping: false,
                },
                unsafe_libyaml::YAML_MAPPING_START_EVENT => Event::Start {
                    anchor: anchor(raw.data.mapping_start.anchor),
                    mapping: true,
                },
                unsafe_libyaml::YAML_SEQUENCE_END_EVENT
                | unsafe_libyaml::YAML_MAPPING_END_EVENT => Event::End,
                unsafe_libyaml::YAML_ALIAS_EVENT => Event::Alias {
                    anchor: anchor(raw.data.alias.anchor).unwrap_or_default(),
                },
                other => {
                    self.done = other == unsafe_libyaml::YAML_STREAM_END_EVENT;
                    Event::Boundary
                }
            };
            let mark = raw.start_mark;
            unsafe_libyaml::yaml_event_delete(raw);
            Some((event, mark))
        }
    }
}

impl Drop for Parser<'_> {
    fn drop(&mut self) {
        // SAFETY: initialized in `new`, deleted once, here.
        unsafe { unsafe_libyaml::yaml_parser_delete(self.state.as_mut_ptr()) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limit(text: &str) -> Option<Limit> {
        prescan(text).err().map(|e| e.limit)
    }

    #[test]
    fn ordinary_files_pass_and_read_as_serde_norway_reads_them() {
        let text = "\
/**:
  ros__parameters:
    horizon: 0.5
    base: &base {x: 1, y: [1, 2]}
    copy: *base
cstep_node:
  ros__parameters:
    robot_description: |
      <robot name=\"x\"/>
";
        assert_eq!(limit(text), None);
        let value = from_str(text).unwrap();
        assert_eq!(value, serde_norway::from_str::<Value>(text).unwrap());
        assert_eq!(limit(""), None);
        assert_eq!(limit("%YAML 1.2\n---\na: 1\n"), None);
    }

    #[test]
    fn each_limit_is_refused_where_it_is_passed() {
        let deep = format!("a: {}", "[".repeat(MAX_DEPTH + 10));
        let err = prescan(&deep).unwrap_err();
        assert_eq!(err.limit, Limit::Depth);
        // The mapping holding `a` is the first level: the 64th `[` is one too many.
        assert_eq!((err.line, err.column), (1, 3 + MAX_DEPTH as u64));
        let within = format!("{}{}", "[".repeat(MAX_DEPTH), "]".repeat(MAX_DEPTH));
        assert_eq!(limit(&within), None);

        let many = format!("[{}]", "1,".repeat(MAX_VALUES as usize));
        assert_eq!(limit(&many), Some(Limit::Values));

        let laughs = (1..10).fold(
            "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n".to_owned(),
            |t, i| {
                let refs = vec![format!("*a{}", i - 1); 10].join(", ");
                t + &format!("a{i}: &a{i} [{refs}]\n")
            },
        );
        assert_eq!(limit(&laughs), Some(Limit::Values));
        let long = "x".repeat(1 << 20);
        let wide = format!("a: &a {long}\nb: [{}]\n", vec!["*a"; 20].join(", "));
        assert_eq!(limit(&wide), Some(Limit::ExpandedBytes));

        let key = "k".repeat(MAX_KEY_PATH_BYTES / 2);
        assert_eq!(limit(&format!("{key}: 1\n{key}: 2\n")), None);
        assert_eq!(
            limit(&format!("{key}:\n  {key}: 1\n")),
            Some(Limit::KeyPath)
        );
        assert_eq!(limit("? [a]\n: 1\n"), Some(Limit::CollectionKey));
        assert_eq!(limit("a: &a [1]\n*a : 1\n"), Some(Limit::CollectionKey));

        let tags = "%TAG !t! tag:x,2000:\n".repeat(MAX_DIRECTIVES + 1) + "---\na: 1\n";
        let err = prescan(&tags).unwrap_err();
        assert_eq!((err.limit, err.line), (Limit::Directives, 17));
    }

    #[test]
    fn refusals_and_syntax_errors_are_one_line_naming_what_was_wrong() {
        let deep = format!("a: {}", "[".repeat(1000));
        assert_eq!(
            from_str(&deep).unwrap_err().to_string(),
            "refused before reading: values nested more than 64 levels deep (at line 1 column 67)"
        );
        let err = from_str("a: [1,\n").unwrap_err().to_string();
        assert!(err.starts_with("not valid YAML: "), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
    }
}
