//! Reading a ROS message from JSON strictly: a field the message does not have is refused with
//! its path and the known field it most likely misspells (`pose.pose.pos: unknown field, did you
//! mean `position`?`), every other misfit with the path of the field at fault; fields left out
//! still take their ROS defaults ([`super`]).
//!
//! serde_json alone reports neither: with `#[serde(deny_unknown_fields)]` (which every message
//! struct carries) its error names the field but not where it is, and without it a misspelt
//! field is silently dropped and its default scored — `"pos"` for `"position"` would be scored
//! as a robot at the origin. So the text is parsed into a [`serde_json::Value`] first (syntax
//! errors keep serde_json's line and column) and the message is then read from that value by a
//! deserializer that knows each value's path and whose error type catches unknown fields with
//! the names the message expects. A message struct is read from a JSON object only: serde
//! would read an array as the fields in order and `[]` as the default message.

use serde::de::{self, DeserializeOwned, DeserializeSeed, MapAccess, SeqAccess, Visitor};
use serde_json::{Map, Value};

use crate::excerpt::excerpt;

/// JSON text that is not the message asked for.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}{message}", if path.is_empty() { String::new() } else { format!("{path}: ") })]
pub struct JsonError {
    /// Where: the field's path, dotted, `[i]` for an array's element (`pose.pose.pos`,
    /// `ranges[3]`); empty for the text as a whole.
    pub path: String,
    /// What is wrong there.
    pub message: String,
}

/// The message `T` that the JSON `text` holds, read strictly (see the module's documentation).
pub fn from_json<T: DeserializeOwned>(text: &str) -> Result<T, JsonError> {
    let UniqueKeys(value) = serde_json::from_str(text).map_err(|e| JsonError {
        path: String::new(),
        message: e.to_string(),
    })?;
    T::deserialize(Node {
        value,
        path: String::new(),
    })
    .map_err(|misfit| JsonError {
        path: misfit.path.unwrap_or_default(),
        message: misfit.message,
    })
}

/// A JSON value whose objects name each key once. serde_json's [`Value`] keeps the last of two
/// equal keys, so `{"x": 1, "x": 2}` would be read as `x = 2` without a word; this refuses it
/// with serde_json's line and column (its own `Value` visitor has no hook for that).
struct UniqueKeys(Value);

impl<'de> de::Deserialize<'de> for UniqueKeys {
    fn deserialize<D: de::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer
            .deserialize_any(UniqueKeysVisitor)
            .map(UniqueKeys)
    }
}

/// Builds a [`Value`] as serde_json's does, refusing a key an object already has.
struct UniqueKeysVisitor;

impl<'de> Visitor<'de> for UniqueKeysVisitor {
    type Value = Value;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }

    fn visit_bool<E>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }

    fn visit_i64<E>(self, v: i64) -> Result<Value, E> {
        Ok(Value::from(v))
    }

    fn visit_u64<E>(self, v: u64) -> Result<Value, E> {
        Ok(Value::from(v))
    }

    fn visit_f64<E>(self, v: f64) -> Result<Value, E> {
        Ok(Value::from(v))
    }

    fn visit_str<E>(self, v: &str) -> Result<Value, E> {
        Ok(Value::String(v.to_owned()))
    }

    fn visit_string<E>(self, v: String) -> Result<Value, E> {
        Ok(Value::String(v))
    }

    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut items = Vec::new();
        while let Some(UniqueKeys(item)) = seq.next_element()? {
            items.push(item);
        }
        Ok(Value::Array(items))
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut object = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if object.contains_key(&key) {
                return Err(de::Error::custom(format_args!(
                    "duplicate key `{}`",
                    excerpt(&key)
                )));
            }
            let UniqueKeys(value) = map.next_value()?;
            object.insert(key, value);
        }
        Ok(Value::Object(object))
    }
}

/// The deserializer's error: what is wrong, and where once the value at fault is known.
#[derive(Debug)]
struct Misfit {
    path: Option<String>,
    message: String,
}

impl Misfit {
    /// The error located at `path`, unless a deeper value already located it.
    fn at(mut self, path: &str) -> Self {
        self.path.get_or_insert_with(|| path.to_owned());
        self
    }
}

impl std::fmt::Display for Misfit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Misfit {}

impl de::Error for Misfit {
    fn custom<M: std::fmt::Display>(message: M) -> Self {
        Self {
            path: None,
            message: message.to_string(),
        }
    }

    /// The field's name is the last part of its path; the message names what it may mean.
    fn unknown_field(field: &str, expected: &'static [&'static str]) -> Self {
        let message = match cstep_core::suggest::nearest(field, expected.iter().copied()) {
            Some(meant) => format!("unknown field, did you mean `{meant}`?"),
            None if expected.is_empty() => "unknown field (this message has none)".to_owned(),
            None => format!("unknown field (the fields here: {})", expected.join(", ")),
        };
        Self {
            path: None,
            message,
        }
    }
}

/// The path of `key` in the object at `path` (a long key by its start and length, [`excerpt`]).
fn child(path: &str, key: &str) -> String {
    let key = excerpt(key);
    if path.is_empty() {
        key.into_owned()
    } else {
        format!("{path}.{key}")
    }
}

/// A JSON value and its path in the text.
struct Node {
    value: Value,
    path: String,
}

impl<'de> de::Deserializer<'de> for Node {
    type Error = Misfit;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Misfit> {
        match self.value {
            Value::Null => visitor.visit_unit(),
            Value::Bool(b) => visitor.visit_bool(b),
            Value::Number(n) => match (n.as_u64(), n.as_i64(), n.as_f64()) {
                (Some(u), _, _) => visitor.visit_u64(u),
                (None, Some(i), _) => visitor.visit_i64(i),
                (None, None, f) => visitor.visit_f64(f.unwrap_or(f64::NAN)),
            },
            Value::String(s) => visitor.visit_string(s),
            Value::Array(items) => {
                let total = items.len();
                let mut elements = Elements {
                    items: items.into_iter().enumerate(),
                    path: &self.path,
                };
                let value = visitor.visit_seq(&mut elements)?;
                let left = elements.items.len();
                if left > 0 {
                    return Err(de::Error::invalid_length(
                        total,
                        &format!("{} elements", total - left).as_str(),
                    ));
                }
                Ok(value)
            }
            Value::Object(fields) => visitor.visit_map(Fields {
                fields: fields.into_iter(),
                pending: None,
                path: &self.path,
            }),
        }
    }

    /// A message (a struct) from an object only; serde would take an array's elements as the
    /// fields in order, and `[]` as the default message.
    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Misfit> {
        let kind = match &self.value {
            Value::Object(_) => return self.deserialize_any(visitor),
            Value::Array(_) => "an array",
            Value::String(_) => "a string",
            Value::Number(_) => "a number",
            Value::Bool(_) => "a boolean",
            Value::Null => "null",
        };
        Err(de::Error::custom(format_args!(
            "expected a JSON object, got {kind} (a message's fields go by their ROS names)"
        )))
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string bytes byte_buf
        option unit unit_struct newtype_struct seq tuple tuple_struct map enum identifier
        ignored_any
    }
}

/// An array's elements, each with its path.
struct Elements<'p> {
    items: std::iter::Enumerate<std::vec::IntoIter<Value>>,
    path: &'p str,
}

impl<'de> SeqAccess<'de> for Elements<'_> {
    type Error = Misfit;

    fn next_element_seed<T: DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, Misfit> {
        let Some((i, value)) = self.items.next() else {
            return Ok(None);
        };
        let path = format!("{}[{i}]", self.path);
        // Errors raised after the element was read (a `deserialize_with` check) are located
        // here too.
        seed.deserialize(Node {
            value,
            path: path.clone(),
        })
        .map(Some)
        .map_err(|e| e.at(&path))
    }

    fn size_hint(&self) -> Option<usize> {
        Some(self.items.len())
    }
}

/// An object's fields, each with its path.
struct Fields<'p> {
    fields: <Map<String, Value> as IntoIterator>::IntoIter,
    /// The value of the key just read, with its path.
    pending: Option<(Value, String)>,
    path: &'p str,
}

impl<'de> MapAccess<'de> for Fields<'_> {
    type Error = Misfit;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, Misfit> {
        let Some((key, value)) = self.fields.next() else {
            return Ok(None);
        };
        let path = child(self.path, &key);
        let read = seed
            .deserialize(de::value::StringDeserializer::<Misfit>::new(key))
            .map_err(|e| e.at(&path))?;
        self.pending = Some((value, path));
        Ok(Some(read))
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, Misfit> {
        let (value, path) = self
            .pending
            .take()
            .ok_or_else(|| de::Error::custom("a value asked for before its key"))?;
        seed.deserialize(Node {
            value,
            path: path.clone(),
        })
        .map_err(|e| e.at(&path))
    }

    fn size_hint(&self) -> Option<usize> {
        Some(self.fields.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros::messages::{LaserScan, Odometry};

    fn refusal<T: DeserializeOwned + std::fmt::Debug>(json: &str) -> String {
        let e = from_json::<T>(json).unwrap_err().to_string();
        assert!(!e.contains('\n'), "{e}");
        e
    }

    #[test]
    fn misspelt_fields_are_refused_with_their_path_and_the_field_meant() {
        // Regression: this was scored as a robot at the origin, at rest.
        let odom = r#"{"pose": {"pose": {"pos": {"x": 3.0}}},
                       "twist": {"twist": {"linaer": {"x": 1.0}}}}"#;
        assert_eq!(
            refusal::<Odometry>(odom),
            "pose.pose.pos: unknown field, did you mean `position`?"
        );
        assert_eq!(
            refusal::<Odometry>(r#"{"twist": {"twist": {"linaer": {"x": 1.0}}}}"#),
            "twist.twist.linaer: unknown field, did you mean `linear`?"
        );
        assert_eq!(
            refusal::<LaserScan>(r#"{"header": {"stamp": {"secs": 1}}}"#),
            "header.stamp.secs: unknown field, did you mean `sec`?"
        );
        assert_eq!(
            refusal::<Odometry>(r#"{"velocity": 1}"#),
            "velocity: unknown field (the fields here: header, child_frame_id, pose, twist)"
        );
        let long = "k".repeat(100_000);
        assert_eq!(
            refusal::<Odometry>(&format!(r#"{{"pose": {{"{long}": 1}}}}"#)),
            format!(
                "pose.{}… (100000 characters): unknown field (the fields here: pose, \
                 covariance)",
                "k".repeat(80)
            )
        );
    }

    /// Before, the last of two equal keys won silently: this was a robot at x = 2.
    #[test]
    fn a_key_given_twice_is_refused_with_its_place() {
        let error =
            from_json::<Odometry>(r#"{"pose": {"pose": {"position": {"x": 1.0, "x": 2.0}}}}"#)
                .unwrap_err();
        assert!(error.message.contains("duplicate key `x`"), "{error}");
        assert!(error.message.contains("line 1 column"), "{error}");
        let error = from_json::<Odometry>(r#"{"pose": {}, "pose": {}}"#).unwrap_err();
        assert!(error.message.contains("duplicate key `pose`"), "{error}");
        // Equal keys in different objects are no duplicates.
        let odom: Odometry = from_json(
            r#"{"pose": {"pose": {"position": {"x": 1.0}, "orientation": {"x": 0.0, "w": 1.0}}}}"#,
        )
        .unwrap();
        assert_eq!(odom.pose.pose.position.x, 1.0);
    }

    #[test]
    fn fields_left_out_take_their_ros_defaults() {
        let odom: Odometry =
            from_json(r#"{"pose": {"pose": {"position": {"x": 1.0, "y": 2.0}}}}"#).unwrap();
        assert_eq!(odom.pose.pose.position.x, 1.0);
        assert_eq!(odom.pose.pose.orientation.w, 1.0);
        assert_eq!(odom.twist.twist.linear.x, 0.0);
        assert_eq!(odom.pose.covariance, [0.0; 36]);
        assert_eq!(from_json::<Odometry>("{}").unwrap(), Odometry::default());
    }

    #[test]
    fn every_misfit_names_the_path_of_the_value_at_fault() {
        for (json, expected) in [
            (
                r#"{"pose": {"pose": {"position": {"x": "one"}}}}"#,
                "pose.pose.position.x: invalid type: string \"one\", expected f64",
            ),
            (
                r#"{"pose": {"covariance": [1, 2]}}"#,
                "pose.covariance: invalid length 2, expected an array of length 36",
            ),
            (
                r#"{"pose": {"pose": []}}"#,
                "pose.pose: expected a JSON object, got an array (a message's fields go by \
                 their ROS names)",
            ),
            (
                r#"{"header": {"stamp": {"sec": 1.5}}}"#,
                "header.stamp.sec: invalid type: floating point `1.5`, expected i32",
            ),
        ] {
            assert_eq!(refusal::<Odometry>(json), expected, "{json}");
        }
        assert_eq!(
            refusal::<LaserScan>(r#"{"ranges": [1.0, "far"]}"#),
            "ranges[1]: invalid value: string \"far\", expected a number, null, or one of \
             \"inf\", \"-inf\", \"nan\""
        );
        assert_eq!(
            refusal::<LaserScan>(r#"{"angle_increment": 1e300}"#),
            format!(
                "angle_increment: 1e300 does not fit the message's float32 (magnitudes {:e} \
                 to {:e})",
                f32::from_bits(1),
                f32::MAX
            )
        );
        assert!(refusal::<LaserScan>(r#"{"ranges": [1.0,"#).contains("line 1"));
        assert_eq!(
            refusal::<LaserScan>("[]"),
            "expected a JSON object, got an array (a message's fields go by their ROS names)"
        );
    }

    #[test]
    fn scans_read_rosbridge_nulls_and_named_non_finite_values() {
        let scan: LaserScan =
            from_json(r#"{"ranges":[1.5, null, "-inf", "nan", "inf", 2]}"#).unwrap();
        assert_eq!(scan.ranges[..3], [1.5, f32::INFINITY, f32::NEG_INFINITY]);
        assert!(scan.ranges[3].is_nan());
        assert_eq!(scan.ranges[4..], [f32::INFINITY, 2.0]);
        let scan: LaserScan =
            from_json(r#"{"angle_min": -3, "range_max": 3.4e38, "angle_max": 1e-45}"#).unwrap();
        assert_eq!(
            (scan.angle_min, scan.range_max, scan.angle_max),
            (-3.0, 3.4e38, 1e-45)
        );
    }
}
