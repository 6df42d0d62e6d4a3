//! `sensor_msgs/PointCloud2`: the message, and the x, y, z of its points read from its bytes.
//!
//! A cloud describes its own layout — named fields at byte offsets with a datatype each, a
//! point and a row stride, an endianness — and every one of them can be wrong on the wire.
//! [`cloud_points`] checks the layout against the data before it reads a byte and says what is
//! wrong (Nav2's collision monitor dies on a cloud without x/y/z, navigation2 #6166): a cloud
//! is skipped and reported, never a panic. Written by hand: the one maintained decoder,
//! `ros_pointcloud2`, reads into its own message type (`ros2-interfaces-jazzy`), while this
//! node's messages are serde mirrors ([`super`]), and reading three float fields by offset is
//! a few lines.

use serde::{Deserialize, Serialize};

use super::Header;

/// `sensor_msgs/PointField`.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PointField {
    /// Field name (`x`, `y`, `z`, `intensity`, …).
    pub name: String,
    /// Byte offset of the field within a point.
    pub offset: u32,
    /// Datatype, one of the constants [`datatype`] names.
    pub datatype: u8,
    /// Elements in the field.
    pub count: u32,
}

/// `sensor_msgs/PointCloud2`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PointCloud2 {
    /// Acquisition time and the sensor frame.
    pub header: Header,
    /// Rows (1 for an unordered cloud).
    pub height: u32,
    /// Points per row.
    pub width: u32,
    /// The layout of a point.
    pub fields: Vec<PointField>,
    /// Whether multi-byte fields are big-endian.
    pub is_bigendian: bool,
    /// Bytes per point.
    pub point_step: u32,
    /// Bytes per row.
    pub row_step: u32,
    /// The points, `row_step × height` bytes.
    pub data: Vec<u8>,
    /// True when no point is invalid (NaN).
    pub is_dense: bool,
}

/// The datatypes of `sensor_msgs/PointField`.
pub mod datatype {
    /// `INT8`.
    pub const INT8: u8 = 1;
    /// `UINT8`.
    pub const UINT8: u8 = 2;
    /// `INT16`.
    pub const INT16: u8 = 3;
    /// `UINT16`.
    pub const UINT16: u8 = 4;
    /// `INT32`.
    pub const INT32: u8 = 5;
    /// `UINT32`.
    pub const UINT32: u8 = 6;
    /// `FLOAT32`.
    pub const FLOAT32: u8 = 7;
    /// `FLOAT64`.
    pub const FLOAT64: u8 = 8;

    /// The datatype's name in the message definition, for errors.
    pub fn name(datatype: u8) -> String {
        match datatype {
            INT8 => "INT8".into(),
            UINT8 => "UINT8".into(),
            INT16 => "INT16".into(),
            UINT16 => "UINT16".into(),
            INT32 => "INT32".into(),
            UINT32 => "UINT32".into(),
            FLOAT32 => "FLOAT32".into(),
            FLOAT64 => "FLOAT64".into(),
            other => format!("unknown datatype {other}"),
        }
    }
}

/// Why a cloud's points cannot be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CloudError {
    /// A coordinate field is missing.
    #[error("the cloud has no '{0}' field (its fields: {1})")]
    MissingField(&'static str, String),
    /// A coordinate field is not a float.
    #[error("the cloud's '{0}' field is {1}; x, y and z must be FLOAT32 or FLOAT64")]
    NotFloat(&'static str, String),
    /// A coordinate field does not fit in a point.
    #[error("the cloud's '{field}' field ends at byte {end} of a {point_step}-byte point")]
    FieldOutsidePoint {
        /// The field.
        field: &'static str,
        /// Where it ends.
        end: u64,
        /// The point's size.
        point_step: u32,
    },
    /// The strides contradict the size.
    #[error(
        "the cloud's layout does not fit its data: {width} × {height} points of {point_step} \
         bytes in rows of {row_step} bytes need {needed} bytes, it has {len}"
    )]
    LayoutMismatch {
        /// Points per row.
        width: u32,
        /// Rows.
        height: u32,
        /// Bytes per point.
        point_step: u32,
        /// Bytes per row.
        row_step: u32,
        /// Bytes the layout needs.
        needed: u64,
        /// Bytes the data has.
        len: usize,
    },
}

/// Where one coordinate lies in a point, and how it is stored.
#[derive(Debug, Clone, Copy)]
struct Coordinate {
    offset: usize,
    double: bool,
}

/// The x, y, z of the points of `cloud` (in its own frame), at most `max_points` of them: a
/// larger cloud is read every k-th point, for the smallest k that keeps within the bound (a
/// LiDAR's points are ordered by bearing or ring, so a stride thins them evenly). Invalid
/// points (NaN) are kept: the reader counts them.
pub fn cloud_points(cloud: &PointCloud2, max_points: usize) -> Result<Vec<[f32; 3]>, CloudError> {
    let coordinates = ["x", "y", "z"].map(|name| coordinate(cloud, name));
    let [x, y, z] = match coordinates {
        [Ok(x), Ok(y), Ok(z)] => [x, y, z],
        [x, y, z] => {
            return Err([x, y, z]
                .into_iter()
                .find_map(Result::err)
                .expect("one failed"))
        }
    };
    let (width, height) = (cloud.width as u64, cloud.height as u64);
    let (point_step, row_step) = (cloud.point_step as u64, cloud.row_step as u64);
    // u64 products of u32s cannot overflow; their sum can, so it saturates.
    let needed = if width == 0 || height == 0 {
        0
    } else {
        ((height - 1) * row_step).saturating_add(width * point_step)
    };
    if row_step < width * point_step || needed > cloud.data.len() as u64 {
        return Err(CloudError::LayoutMismatch {
            width: cloud.width,
            height: cloud.height,
            point_step: cloud.point_step,
            row_step: cloud.row_step,
            needed,
            len: cloud.data.len(),
        });
    }
    let total = width * height;
    let stride = total.div_ceil(max_points.max(1) as u64).max(1);
    let big = cloud.is_bigendian;
    let mut points = Vec::with_capacity((total / stride) as usize);
    for index in (0..total).step_by(stride as usize) {
        let (row, column) = (index / width, index % width);
        let start = (row * row_step + column * point_step) as usize;
        let point = &cloud.data[start..start + point_step as usize];
        points.push([x, y, z].map(|c| read(point, c, big)));
    }
    Ok(points)
}

/// The field `name` of `cloud`'s layout, checked to be a float inside a point.
fn coordinate(cloud: &PointCloud2, name: &'static str) -> Result<Coordinate, CloudError> {
    let Some(field) = cloud.fields.iter().find(|f| f.name == name) else {
        let names: Vec<&str> = cloud.fields.iter().map(|f| f.name.as_str()).collect();
        return Err(CloudError::MissingField(name, format!("{names:?}")));
    };
    let double = match field.datatype {
        datatype::FLOAT32 => false,
        datatype::FLOAT64 => true,
        other => return Err(CloudError::NotFloat(name, datatype::name(other))),
    };
    let end = field.offset as u64 + if double { 8 } else { 4 };
    if end > cloud.point_step as u64 {
        return Err(CloudError::FieldOutsidePoint {
            field: name,
            end,
            point_step: cloud.point_step,
        });
    }
    Ok(Coordinate {
        offset: field.offset as usize,
        double,
    })
}

/// Coordinate `c` of `point` (bounds checked by [`coordinate`]), narrowed to f32.
fn read(point: &[u8], c: Coordinate, big_endian: bool) -> f32 {
    if c.double {
        let bytes: [u8; 8] = point[c.offset..c.offset + 8].try_into().expect("8 bytes");
        (if big_endian {
            f64::from_be_bytes(bytes)
        } else {
            f64::from_le_bytes(bytes)
        }) as f32
    } else {
        let bytes: [u8; 4] = point[c.offset..c.offset + 4].try_into().expect("4 bytes");
        if big_endian {
            f32::from_be_bytes(bytes)
        } else {
            f32::from_le_bytes(bytes)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn field(name: &str, offset: u32, datatype: u8) -> PointField {
        PointField {
            name: name.into(),
            offset,
            datatype,
            count: 1,
        }
    }

    /// An unordered cloud of `points` as x, y, z, intensity float32s (16 bytes a point).
    fn cloud(points: &[[f32; 3]], big_endian: bool) -> PointCloud2 {
        let mut data = Vec::new();
        for p in points {
            for v in [p[0], p[1], p[2], 1.0] {
                data.extend(if big_endian {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                });
            }
        }
        PointCloud2 {
            height: 1,
            width: points.len() as u32,
            fields: vec![
                field("x", 0, datatype::FLOAT32),
                field("y", 4, datatype::FLOAT32),
                field("z", 8, datatype::FLOAT32),
                field("intensity", 12, datatype::FLOAT32),
            ],
            is_bigendian: big_endian,
            point_step: 16,
            row_step: 16 * points.len() as u32,
            data,
            is_dense: true,
            ..Default::default()
        }
    }

    const POINTS: [[f32; 3]; 3] = [[1.0, 2.0, 3.0], [-0.5, 0.25, f32::NAN], [4.0, -4.0, 0.0]];

    fn same(a: &[[f32; 3]], b: &[[f32; 3]]) -> bool {
        a.len() == b.len()
            && a.iter()
                .flatten()
                .zip(b.iter().flatten())
                .all(|(x, y)| x.to_bits() == y.to_bits())
    }

    #[test]
    fn points_are_read_in_either_byte_order() {
        for big in [false, true] {
            let read = cloud_points(&cloud(&POINTS, big), 1000).unwrap();
            assert!(same(&read, &POINTS), "big-endian {big}: {read:?}");
        }
    }

    #[test]
    fn float64_fields_at_any_offset_and_padded_rows_are_read() {
        // Ordered 2 × 2, z first, float64, 4 bytes of padding per row.
        let mut data = Vec::new();
        for row in 0..2 {
            for column in 0..2 {
                let (x, y, z) = (row as f64, column as f64, 0.5);
                for v in [z, x, y] {
                    data.extend(v.to_le_bytes());
                }
            }
            data.extend([0xAA; 4]);
        }
        let cloud = PointCloud2 {
            height: 2,
            width: 2,
            fields: vec![
                field("z", 0, datatype::FLOAT64),
                field("x", 8, datatype::FLOAT64),
                field("y", 16, datatype::FLOAT64),
            ],
            point_step: 24,
            row_step: 52,
            data,
            ..Default::default()
        };
        let read = cloud_points(&cloud, 100).unwrap();
        let expected = [
            [0.0, 0.0, 0.5],
            [0.0, 1.0, 0.5],
            [1.0, 0.0, 0.5],
            [1.0, 1.0, 0.5],
        ];
        assert!(same(&read, &expected), "{read:?}");
    }

    #[test]
    fn a_cloud_without_xyz_is_refused_naming_the_field_and_what_it_has() {
        let mut c = cloud(&POINTS, false);
        c.fields.retain(|f| f.name != "z");
        let err = cloud_points(&c, 100).unwrap_err();
        assert_eq!(
            err.to_string(),
            r#"the cloud has no 'z' field (its fields: ["x", "y", "intensity"])"#
        );
    }

    #[test]
    fn integer_coordinates_and_fields_past_the_point_are_refused() {
        let mut c = cloud(&POINTS, false);
        c.fields[1].datatype = datatype::UINT16;
        assert_eq!(
            cloud_points(&c, 100).unwrap_err().to_string(),
            "the cloud's 'y' field is UINT16; x, y and z must be FLOAT32 or FLOAT64"
        );
        let mut c = cloud(&POINTS, false);
        c.fields[2].offset = 14;
        assert_eq!(
            cloud_points(&c, 100).unwrap_err(),
            CloudError::FieldOutsidePoint {
                field: "z",
                end: 18,
                point_step: 16
            }
        );
    }

    #[test]
    fn strides_that_overrun_the_data_are_refused() {
        let mut lies = cloud(&POINTS, false);
        lies.row_step = 10; // shorter than a row of points
        assert!(matches!(
            cloud_points(&lies, 100),
            Err(CloudError::LayoutMismatch { .. })
        ));
        let mut short = cloud(&POINTS, false);
        short.data.truncate(40);
        let err = cloud_points(&short, 100).unwrap_err().to_string();
        assert!(err.contains("need 48 bytes, it has 40"), "{err}");
        let mut rows = cloud(&POINTS, false);
        rows.height = 2;
        assert!(cloud_points(&rows, 100).is_err());
    }

    #[test]
    fn big_clouds_are_thinned_to_the_bound_by_an_even_stride() {
        let points: Vec<[f32; 3]> = (0..1000).map(|i| [i as f32, 0.0, 0.0]).collect();
        let read = cloud_points(&cloud(&points, false), 300).unwrap();
        // Stride 4: 250 points, every fourth.
        assert_eq!(read.len(), 250);
        assert!(read.iter().enumerate().all(|(k, p)| p[0] == (4 * k) as f32));
        assert!(cloud_points(&cloud(&[], false), 300).unwrap().is_empty());
    }

    proptest! {
        /// Any layout and any bytes: an error or points, never a panic.
        #[test]
        fn arbitrary_clouds_never_panic(
            width in 0u32..40,
            height in 0u32..4,
            point_step in 0u32..40,
            row_step in 0u32..2000,
            offsets in proptest::array::uniform3(0u32..48),
            types in proptest::array::uniform3(0u8..10),
            big in any::<bool>(),
            data in proptest::collection::vec(any::<u8>(), 0..3000),
        ) {
            let fields = ["x", "y", "z"]
                .iter()
                .zip(offsets.iter().zip(types))
                .map(|(name, (&offset, datatype))| field(name, offset, datatype))
                .collect();
            let cloud = PointCloud2 {
                height, width, fields, is_bigendian: big, point_step, row_step, data,
                ..Default::default()
            };
            if let Ok(points) = cloud_points(&cloud, 64) {
                prop_assert!(points.len() <= 64);
            }
        }
    }
}
