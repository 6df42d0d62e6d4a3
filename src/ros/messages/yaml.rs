//! Messages as YAML in the layout `ros2 topic echo` prints: block mappings indented by two,
//! sequence items at their key's indentation, `[]` for empty sequences, `''` for empty strings.
//!
//! Values are printed as the wire carries them: integers as integers, floats with the fewest
//! digits that read back to the same value (always with a `.`, and `.inf`, `-.inf`, `.nan` for
//! the non-finite ones, so both YAML 1.1 readers such as PyYAML and YAML 1.2 readers parse a
//! float), strings plain when no YAML reader could take them for anything else and
//! double-quoted otherwise. The serializer reports `is_human_readable() == false`, so message
//! fields with a JSON-only stand-in (rosbridge's `null` for non-finite ranges) print their real
//! values.
//!
//! Written here rather than with `serde_norway` (used for parameter files): that serializer
//! reports itself human-readable, so scan ranges would print JSON's `null` stand-ins, and it
//! writes exponents without a sign (`1e308`), which YAML 1.1 readers such as PyYAML read as
//! strings.

use std::fmt::{self, Write as _};

use serde::ser::{self, Serialize};

/// `value` as one YAML document (no `---` marker), ending in a newline.
pub fn to_yaml<T: Serialize + ?Sized>(value: &T) -> Result<String, Error> {
    let tree = value.serialize(TreeSerializer)?;
    let mut out = String::new();
    match &tree {
        Tree::Scalar(s) => writeln!(out, "{s}").expect("writing to a String"),
        Tree::Seq(items) if items.is_empty() => out.push_str("[]\n"),
        Tree::Map(entries) if entries.is_empty() => out.push_str("{}\n"),
        Tree::Seq(items) => write_seq(items, 0, &mut out),
        Tree::Map(entries) => write_map(entries, 0, &mut out),
    }
    Ok(out)
}

/// A value the YAML writer cannot represent (serde's error type for [`to_yaml`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Error(String);

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Error {}

impl ser::Error for Error {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        Self(msg.to_string())
    }
}

/// A serialized value, before layout.
#[derive(Debug, Clone, PartialEq)]
enum Tree {
    /// A scalar, already in its YAML spelling.
    Scalar(String),
    /// A sequence.
    Seq(Vec<Tree>),
    /// A mapping; keys already in their YAML spelling.
    Map(Vec<(String, Tree)>),
}

fn write_map(entries: &[(String, Tree)], indent: usize, out: &mut String) {
    let pad = " ".repeat(indent);
    for (key, value) in entries {
        match value {
            Tree::Scalar(s) => writeln!(out, "{pad}{key}: {s}"),
            Tree::Seq(items) if items.is_empty() => writeln!(out, "{pad}{key}: []"),
            Tree::Map(inner) if inner.is_empty() => writeln!(out, "{pad}{key}: {{}}"),
            Tree::Seq(items) => {
                writeln!(out, "{pad}{key}:").expect("writing to a String");
                write_seq(items, indent, out);
                Ok(())
            }
            Tree::Map(inner) => {
                writeln!(out, "{pad}{key}:").expect("writing to a String");
                write_map(inner, indent + 2, out);
                Ok(())
            }
        }
        .expect("writing to a String");
    }
}

fn write_seq(items: &[Tree], indent: usize, out: &mut String) {
    let pad = " ".repeat(indent);
    for item in items {
        match item {
            Tree::Scalar(s) => writeln!(out, "{pad}- {s}").expect("writing to a String"),
            Tree::Seq(inner) if inner.is_empty() => {
                writeln!(out, "{pad}- []").expect("writing to a String")
            }
            Tree::Map(inner) if inner.is_empty() => {
                writeln!(out, "{pad}- {{}}").expect("writing to a String")
            }
            nested => {
                // Lay the item out two deeper, then put the dash into its first indentation.
                let mut block = String::new();
                match nested {
                    Tree::Seq(inner) => write_seq(inner, indent + 2, &mut block),
                    Tree::Map(inner) => write_map(inner, indent + 2, &mut block),
                    Tree::Scalar(_) => unreachable!("scalars are handled above"),
                }
                out.push_str(&pad);
                out.push_str("- ");
                out.push_str(&block[indent + 2..]);
            }
        }
    }
}

/// A float with the fewest digits that read back to it, spelled so that YAML 1.1 and 1.2
/// readers alike take it for a float: `1.0`, `0.25`, `1.0e-07` → `1.0e-7`, `.inf`, `.nan`.
fn float_scalar(shortest: String, value: f64) -> String {
    if value.is_nan() {
        return ".nan".into();
    }
    if value.is_infinite() {
        return if value > 0.0 { ".inf" } else { "-.inf" }.into();
    }
    let (mantissa, exponent) = match shortest.split_once('e') {
        Some((m, e)) => (m.to_owned(), Some(e.to_owned())),
        None => (shortest, None),
    };
    let mantissa = if mantissa.contains('.') {
        mantissa
    } else {
        format!("{mantissa}.0")
    };
    match exponent {
        Some(e) if e.starts_with('-') => format!("{mantissa}e{e}"),
        Some(e) => format!("{mantissa}e+{e}"),
        None => mantissa,
    }
}

/// Words YAML 1.1 or 1.2 readers turn into booleans or null when plain.
const RESERVED_WORDS: [&str; 12] = [
    "y", "n", "yes", "no", "true", "false", "on", "off", "null", "nan", "inf", "infinity",
];

/// A string as a YAML scalar: plain when it can only read back as this string, else
/// double-quoted with YAML escapes.
fn string_scalar(s: &str) -> String {
    if s.is_empty() {
        return "''".into();
    }
    let plain = s
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '/' || c == '_')
        && !s.ends_with(' ')
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '/' | '-' | ' '))
        && !RESERVED_WORDS.contains(&s.to_ascii_lowercase().as_str());
    if plain {
        return s.to_owned();
    }
    let mut quoted = String::with_capacity(s.len() + 2);
    quoted.push('"');
    for c in s.chars() {
        match c {
            '"' => quoted.push_str("\\\""),
            '\\' => quoted.push_str("\\\\"),
            '\n' => quoted.push_str("\\n"),
            '\t' => quoted.push_str("\\t"),
            '\r' => quoted.push_str("\\r"),
            c if c.is_control() || matches!(c, '\u{feff}' | '\u{fffe}' | '\u{ffff}') => {
                write!(quoted, "\\u{:04x}", c as u32).expect("writing to a String")
            }
            c => quoted.push(c),
        }
    }
    quoted.push('"');
    quoted
}

/// Serializes any value into a [`Tree`].
struct TreeSerializer;

/// Collects sequence items (sequences, tuples and their variants).
struct SeqBuilder {
    items: Vec<Tree>,
    variant: Option<&'static str>,
}

/// Collects mapping entries (maps, structs and their variants).
struct MapBuilder {
    entries: Vec<(String, Tree)>,
    next_key: Option<String>,
    variant: Option<&'static str>,
}

fn wrap(variant: Option<&'static str>, tree: Tree) -> Tree {
    match variant {
        Some(name) => Tree::Map(vec![(string_scalar(name), tree)]),
        None => tree,
    }
}

/// The text of a map key (keys must be scalars).
fn key_text(tree: Tree) -> Result<String, Error> {
    match tree {
        Tree::Scalar(s) => Ok(s),
        _ => Err(Error("a mapping key must be a scalar".into())),
    }
}

/// Booleans and integers print as Rust writes them, which every YAML reader takes back.
macro_rules! plain_scalars {
    ($($method:ident: $t:ty),*) => {$(
        fn $method(self, v: $t) -> Result<Tree, Error> {
            Ok(Tree::Scalar(v.to_string()))
        }
    )*};
}

impl ser::Serializer for TreeSerializer {
    type Ok = Tree;
    type Error = Error;
    type SerializeSeq = SeqBuilder;
    type SerializeTuple = SeqBuilder;
    type SerializeTupleStruct = SeqBuilder;
    type SerializeTupleVariant = SeqBuilder;
    type SerializeMap = MapBuilder;
    type SerializeStruct = MapBuilder;
    type SerializeStructVariant = MapBuilder;

    fn is_human_readable(&self) -> bool {
        false
    }

    plain_scalars!(
        serialize_bool: bool,
        serialize_i8: i8,
        serialize_i16: i16,
        serialize_i32: i32,
        serialize_i64: i64,
        serialize_u8: u8,
        serialize_u16: u16,
        serialize_u32: u32,
        serialize_u64: u64
    );
    fn serialize_f32(self, v: f32) -> Result<Tree, Error> {
        Ok(Tree::Scalar(float_scalar(format!("{v:?}"), v as f64)))
    }
    fn serialize_f64(self, v: f64) -> Result<Tree, Error> {
        Ok(Tree::Scalar(float_scalar(format!("{v:?}"), v)))
    }
    fn serialize_char(self, v: char) -> Result<Tree, Error> {
        Ok(Tree::Scalar(string_scalar(&v.to_string())))
    }
    fn serialize_str(self, v: &str) -> Result<Tree, Error> {
        Ok(Tree::Scalar(string_scalar(v)))
    }
    fn serialize_bytes(self, v: &[u8]) -> Result<Tree, Error> {
        Ok(Tree::Seq(
            v.iter().map(|b| Tree::Scalar(b.to_string())).collect(),
        ))
    }
    fn serialize_none(self) -> Result<Tree, Error> {
        Ok(Tree::Scalar("null".into()))
    }
    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> Result<Tree, Error> {
        value.serialize(self)
    }
    fn serialize_unit(self) -> Result<Tree, Error> {
        Ok(Tree::Scalar("null".into()))
    }
    fn serialize_unit_struct(self, _name: &'static str) -> Result<Tree, Error> {
        Ok(Tree::Scalar("null".into()))
    }
    fn serialize_unit_variant(
        self,
        _name: &'static str,
        _index: u32,
        variant: &'static str,
    ) -> Result<Tree, Error> {
        Ok(Tree::Scalar(string_scalar(variant)))
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        _name: &'static str,
        value: &T,
    ) -> Result<Tree, Error> {
        value.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _name: &'static str,
        _index: u32,
        variant: &'static str,
        value: &T,
    ) -> Result<Tree, Error> {
        Ok(wrap(Some(variant), value.serialize(self)?))
    }
    fn serialize_seq(self, len: Option<usize>) -> Result<SeqBuilder, Error> {
        Ok(SeqBuilder {
            items: Vec::with_capacity(len.unwrap_or(0)),
            variant: None,
        })
    }
    fn serialize_tuple(self, len: usize) -> Result<SeqBuilder, Error> {
        self.serialize_seq(Some(len))
    }
    fn serialize_tuple_struct(self, _name: &'static str, len: usize) -> Result<SeqBuilder, Error> {
        self.serialize_seq(Some(len))
    }
    fn serialize_tuple_variant(
        self,
        _name: &'static str,
        _index: u32,
        variant: &'static str,
        len: usize,
    ) -> Result<SeqBuilder, Error> {
        Ok(SeqBuilder {
            items: Vec::with_capacity(len),
            variant: Some(variant),
        })
    }
    fn serialize_map(self, len: Option<usize>) -> Result<MapBuilder, Error> {
        Ok(MapBuilder {
            entries: Vec::with_capacity(len.unwrap_or(0)),
            next_key: None,
            variant: None,
        })
    }
    fn serialize_struct(self, _name: &'static str, len: usize) -> Result<MapBuilder, Error> {
        self.serialize_map(Some(len))
    }
    fn serialize_struct_variant(
        self,
        _name: &'static str,
        _index: u32,
        variant: &'static str,
        len: usize,
    ) -> Result<MapBuilder, Error> {
        Ok(MapBuilder {
            entries: Vec::with_capacity(len),
            next_key: None,
            variant: Some(variant),
        })
    }
}

impl SeqBuilder {
    fn push<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Error> {
        self.items.push(value.serialize(TreeSerializer)?);
        Ok(())
    }
    fn finish(self) -> Result<Tree, Error> {
        Ok(wrap(self.variant, Tree::Seq(self.items)))
    }
}

/// serde's four sequence-like traits differ only in the method's name: one body for all.
macro_rules! sequence_builder {
    ($($trait:ident :: $method:ident),*) => {$(
        impl ser::$trait for SeqBuilder {
            type Ok = Tree;
            type Error = Error;
            fn $method<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Error> {
                self.push(value)
            }
            fn end(self) -> Result<Tree, Error> {
                self.finish()
            }
        }
    )*};
}

sequence_builder!(
    SerializeSeq::serialize_element,
    SerializeTuple::serialize_element,
    SerializeTupleStruct::serialize_field,
    SerializeTupleVariant::serialize_field
);

impl MapBuilder {
    fn field<T: Serialize + ?Sized>(&mut self, key: &str, value: &T) -> Result<(), Error> {
        self.entries
            .push((string_scalar(key), value.serialize(TreeSerializer)?));
        Ok(())
    }
    fn finish(self) -> Result<Tree, Error> {
        Ok(wrap(self.variant, Tree::Map(self.entries)))
    }
}

impl ser::SerializeMap for MapBuilder {
    type Ok = Tree;
    type Error = Error;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, key: &T) -> Result<(), Error> {
        self.next_key = Some(key_text(key.serialize(TreeSerializer)?)?);
        Ok(())
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Error> {
        let key = self
            .next_key
            .take()
            .ok_or_else(|| Error("a mapping value came without its key".into()))?;
        self.entries.push((key, value.serialize(TreeSerializer)?));
        Ok(())
    }
    fn end(self) -> Result<Tree, Error> {
        self.finish()
    }
}

impl ser::SerializeStruct for MapBuilder {
    type Ok = Tree;
    type Error = Error;
    fn serialize_field<T: Serialize + ?Sized>(
        &mut self,
        key: &'static str,
        value: &T,
    ) -> Result<(), Error> {
        self.field(key, value)
    }
    fn end(self) -> Result<Tree, Error> {
        self.finish()
    }
}

impl ser::SerializeStructVariant for MapBuilder {
    type Ok = Tree;
    type Error = Error;
    fn serialize_field<T: Serialize + ?Sized>(
        &mut self,
        key: &'static str,
        value: &T,
    ) -> Result<(), Error> {
        self.field(key, value)
    }
    fn end(self) -> Result<Tree, Error> {
        self.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros::messages::{
        DiagnosticArray, DiagnosticStatus, Empowerment, Header, KeyValue, LaserScan, Marker,
        MarkerArray, Point, Time,
    };

    #[test]
    fn floats_read_back_as_the_same_floats_in_yaml_1_1_spelling() {
        let cases = [
            (1.0, "1.0"),
            (0.25, "0.25"),
            (-3.5, "-3.5"),
            (1e-7, "1.0e-7"),
            (1.5e300, "1.5e+300"),
            (1e16, "1.0e+16"),
            (f64::INFINITY, ".inf"),
            (f64::NEG_INFINITY, "-.inf"),
            (f64::NAN, ".nan"),
        ];
        for (value, shown) in cases {
            assert_eq!(float_scalar(format!("{value:?}"), value), shown);
            if value.is_finite() {
                assert_eq!(shown.parse::<f64>().unwrap(), value);
            }
        }
        // f32 values print their own shortest digits, not those of the widened f64.
        assert_eq!(to_yaml(&0.1_f32).unwrap(), "0.1\n");
    }

    #[test]
    fn strings_are_plain_only_when_nothing_else_could_be_read() {
        for plain in [
            "odom",
            "base_link",
            "/cstep/markers",
            "every trajectory collides",
        ] {
            assert_eq!(string_scalar(plain), plain);
        }
        let quoted = [
            ("", "''"),
            ("yes", "\"yes\""),
            ("Off", "\"Off\""),
            ("null", "\"null\""),
            ("1.5", "\"1.5\""),
            ("cstep: empowerment", "\"cstep: empowerment\""),
            ("a \"b\"\n\\", "\"a \\\"b\\\"\\n\\\\\""),
            ("bell\u{7}", "\"bell\\u0007\""),
            ("- x", "\"- x\""),
            ("# not a comment", "\"# not a comment\""),
            ("trailing ", "\"trailing \""),
        ];
        for (text, shown) in quoted {
            assert_eq!(string_scalar(text), shown, "{text:?}");
        }
    }

    #[test]
    fn layout_matches_ros2_topic_echo() {
        let diagnostics = DiagnosticArray {
            header: Header {
                stamp: Time { sec: 3, nanosec: 5 },
                frame_id: String::new(),
            },
            status: vec![DiagnosticStatus {
                level: 1,
                name: "cstep: empowerment".into(),
                message: "scoring".into(),
                hardware_id: "cstep".into(),
                values: vec![KeyValue {
                    key: "scans_scored".into(),
                    value: "12".into(),
                }],
            }],
        };
        let expected = "\
header:
  stamp:
    sec: 3
    nanosec: 5
  frame_id: ''
status:
- level: 1
  name: \"cstep: empowerment\"
  message: scoring
  hardware_id: cstep
  values:
  - key: scans_scored
    value: \"12\"
";
        assert_eq!(to_yaml(&diagnostics).unwrap(), expected);
    }

    #[test]
    fn non_finite_scan_ranges_print_their_real_values_and_empty_lists_print_brackets() {
        let scan = LaserScan {
            ranges: vec![1.5, f32::INFINITY, f32::NAN, f32::NEG_INFINITY],
            ..Default::default()
        };
        let text = to_yaml(&scan).unwrap();
        assert!(
            text.contains("ranges:\n- 1.5\n- .inf\n- .nan\n- -.inf\n"),
            "{text}"
        );
        assert!(text.contains("intensities: []\n"), "{text}");
    }

    #[test]
    fn messages_read_back_from_their_yaml() {
        let empowerment = Empowerment {
            header: Header {
                stamp: Time {
                    sec: 1000,
                    nanosec: 7,
                },
                frame_id: "odom".into(),
            },
            empowerment: 2.0_f64.ln(),
            reachable_volume: 1e-9,
            free_volume: 123456789.125,
            num_trajectories: 150,
            valid: true,
            status: "ok".into(),
            ..Default::default()
        };
        let back: Empowerment = serde_norway::from_str(&to_yaml(&empowerment).unwrap()).unwrap();
        assert_eq!(back, empowerment);

        let markers = MarkerArray {
            markers: vec![
                Marker {
                    kind: Marker::POINTS,
                    points: vec![Point {
                        x: 0.1,
                        y: -2.0,
                        z: 1.0,
                    }],
                    ..Default::default()
                },
                Marker::default(),
            ],
        };
        let text = to_yaml(&markers).unwrap();
        assert!(
            text.starts_with("markers:\n- header:\n    stamp:\n"),
            "{text}"
        );
        assert!(text.contains("\n  type: 8\n"), "{text}");
        let back: MarkerArray = serde_norway::from_str(&text).unwrap();
        assert_eq!(back, markers);
    }
}
