//! The robot description read from a URDF file: mass, inertia, rotor coefficients, limits and
//! collision shape — everything the dynamics model needs, validated once at load time.
//!
//! Standard URDF elements (links, inertials, collision geometry) are parsed with `urdf-rs`.
//! The rotor and airframe coefficients live in a non-standard `<properties>` element (the
//! convention of the gym-pybullet-drones family of simulators), which `urdf-rs` drops, so it is
//! read with `roxmltree`. Every problem becomes one [`UrdfError`] whose message names the file
//! and the offending element, attribute or value; loading never panics.

use std::path::Path;

use nalgebra::Vector3;

use crate::excerpt::excerpt;

/// Gravitational acceleration used for every derived quantity, m/s² (the value the Crazyflie
/// constants in the facts sheet were derived with: hover 14 468 rpm, max 21 703 rpm).
pub const GRAVITY: f64 = 9.8;

/// Converts rotor speeds from rpm to rad/s.
pub const RPM_TO_RAD_PER_S: f64 = 2.0 * std::f64::consts::PI / 60.0;

/// Why a URDF could not be turned into a [`RobotDescription`]. Each message starts with the
/// file (or source name) and names the missing or bad element, attribute or value.
#[derive(Debug, thiserror::Error)]
pub enum UrdfError {
    /// The file could not be read, or is not a regular file of at most
    /// [`crate::input::file::MAX_INPUT_FILE_BYTES`].
    #[error("{file}: cannot read the file: {error}")]
    Io {
        /// The file that was asked for.
        file: String,
        /// What the operating system said.
        error: std::io::Error,
    },
    /// The text is not well-formed XML.
    #[error("{file}: not well-formed XML: {message}")]
    Xml {
        /// The file or source name.
        file: String,
        /// The parser's message, with line and column.
        message: String,
    },
    /// Well-formed XML that is not a usable URDF (wrong root, no links, several root links,
    /// or an element `urdf-rs` rejects).
    #[error("{file}: not a valid URDF: {message}")]
    Structure {
        /// The file or source name.
        file: String,
        /// What is wrong.
        message: String,
    },
    /// A required element or attribute is absent.
    #[error("{file}: {what} is missing")]
    Missing {
        /// The file or source name.
        file: String,
        /// The missing item, e.g. `<properties> attribute 'kf'`.
        what: String,
    },
    /// A value is present but unusable (not a number, NaN, infinite or out of range).
    #[error("{file}: {field} must be {requirement}, got \"{}\"", excerpt(value))]
    Invalid {
        /// The file or source name.
        file: String,
        /// The offending field, e.g. `link 'body' <inertial> 'mass'`.
        field: String,
        /// What the value must be, e.g. `a positive number`.
        requirement: &'static str,
        /// The value as written (or as parsed, for values `urdf-rs` converted).
        value: String,
    },
    /// The base link has no collision shape the model can use.
    #[error(
        "{file}: base link '{link}' has no usable <collision> geometry \
         (need a cylinder, sphere, box or capsule)"
    )]
    NoCollision {
        /// The file or source name.
        file: String,
        /// The base link's name.
        link: String,
    },
    /// A wheeled model was asked for, and the URDF has no wheels it can drive on.
    #[error(
        "{file}: no wheels found: looked for continuous or revolute joints turning about the \
         robot's lateral (y) axis whose child link has a <collision> <cylinder> along that axis, \
         at least one on the left (y > 0) and one on the right (y < 0); {found}"
    )]
    NoWheels {
        /// The file or source name.
        file: String,
        /// What the search found instead, e.g. `found 1 wheel, none on the right`.
        found: String,
    },
}

/// A multirotor's physical description: what the dynamics model, the collision checks and the
/// speed governor need, in SI units (rotor speeds in rpm).
#[derive(Debug, Clone, PartialEq)]
pub struct RobotDescription {
    /// The `<robot name>`.
    pub name: String,
    /// Where the description came from (a path or a caller-chosen name), for messages.
    pub source: String,
    /// Total mass, kg: the sum of every link's `<inertial>` mass (links without one are
    /// massless, as URDF specifies).
    pub mass: f64,
    /// Principal moments of inertia (Ixx, Iyy, Izz) of the base link about its centre of mass,
    /// kg·m². Products of inertia and the other links' inertia are neglected: in a multirotor
    /// URDF they are massless rotor markers or tiny.
    pub inertia: Vector3<f64>,
    /// Distance from the centre to each rotor axis, m (rotors on the diagonals: X configuration).
    pub arm: f64,
    /// Rotor thrust coefficient: thrust = kf · rpm², N/rpm².
    pub kf: f64,
    /// Rotor drag-torque coefficient: yaw reaction torque = km · rpm², N·m/rpm².
    pub km: f64,
    /// Maximum total thrust over weight.
    pub thrust_to_weight: f64,
    /// Maximum flight speed, m/s (`max_speed_kmh` / 3.6).
    pub max_speed: f64,
    /// Body-frame linear drag coefficients (x, y, z): the drag force on axis i is
    /// −c_i · (Σ rotor speeds in rad/s) · v_i, N per (m/s · rad/s). x and y are equal (the
    /// URDF gives one horizontal coefficient, `drag_coeff_xy`).
    pub drag_coefficients: Vector3<f64>,
    /// Ground-effect coefficient (kept for simulators that model it; rollouts do not, as they
    /// know no floor distance).
    pub ground_effect_coefficient: f64,
    /// Propeller radius, m.
    pub prop_radius: f64,
    /// Radius of the vertical cylinder around the base link's collision geometry, m: the
    /// clearance the robot needs in the horizontal plane.
    pub collision_radius: f64,
    /// Vertical extent of the base link's collision geometry, m.
    pub collision_height: f64,
    /// Gravitational acceleration, m/s² ([`GRAVITY`]).
    pub gravity: f64,
}

/// The text of the URDF at `path` and the path as error messages name it.
pub(crate) fn read_urdf(path: &Path) -> Result<(String, String), UrdfError> {
    let file = path.display().to_string();
    let xml = crate::input::file::read_to_string(path).map_err(|error| UrdfError::Io {
        file: file.clone(),
        error,
    })?;
    Ok((xml, file))
}

impl RobotDescription {
    /// Reads and validates the URDF at `path`; messages name the path as given.
    pub fn load(path: &Path) -> Result<Self, UrdfError> {
        let (xml, file) = read_urdf(path)?;
        Self::from_str(&xml, &file)
    }

    /// Parses and validates URDF text; `source` names it in error messages (a path, or e.g.
    /// `"<inline>"`).
    pub fn from_str(xml: &str, source: &str) -> Result<Self, UrdfError> {
        let file = source.to_string();
        let doc = document(xml, &file)?;
        let root = doc.root_element();
        let props = Properties::read(&root, &file)?;
        let robot = parse_robot(xml, &root, &file)?;
        let base = base_link(&robot, &file)?;

        // urdf-rs fills in a zero inertial when the element is absent; the base link must have
        // a real one, so check the XML itself.
        let has_inertial = root
            .children()
            .filter(|n| n.has_tag_name("link") && n.attribute("name") == Some(base.name.as_str()))
            .any(|link| element(&link, "inertial").is_some());
        if !has_inertial {
            return Err(UrdfError::Missing {
                file,
                what: format!("<inertial> of base link '{}'", base.name),
            });
        }

        let mut mass = 0.0;
        for link in &robot.links {
            let value = link.inertial.mass.value;
            let field = format!("link '{}' <mass> 'value'", link.name);
            if std::ptr::eq(link, base) {
                mass += positive(value, &field, &file)?;
            } else {
                mass += non_negative(value, &field, &file)?;
            }
        }
        let inertia = &base.inertial.inertia;
        let moment = |value: f64, name: &str| {
            positive(
                value,
                &format!("link '{}' <inertia> '{name}'", base.name),
                &file,
            )
        };
        let inertia = Vector3::new(
            moment(inertia.ixx, "ixx")?,
            moment(inertia.iyy, "iyy")?,
            moment(inertia.izz, "izz")?,
        );

        let (collision_radius, collision_height) = collision_extent(base, &file)?;

        Ok(Self {
            name: robot.name.clone(),
            source: file,
            mass,
            inertia,
            arm: props.arm,
            kf: props.kf,
            km: props.km,
            thrust_to_weight: props.thrust_to_weight,
            max_speed: props.max_speed_kmh / 3.6,
            drag_coefficients: Vector3::new(props.drag_xy, props.drag_xy, props.drag_z),
            ground_effect_coefficient: props.ground_effect,
            prop_radius: props.prop_radius,
            collision_radius,
            collision_height,
            gravity: GRAVITY,
        })
    }

    /// Weight m·g, N.
    pub fn weight(&self) -> f64 {
        self.mass * self.gravity
    }

    /// Rotor speed at which the four rotors together carry the weight, rpm
    /// (14 468 rpm for the Crazyflie 2.x).
    pub fn hover_rpm(&self) -> f64 {
        (self.weight() / (4.0 * self.kf)).sqrt()
    }

    /// Highest rotor speed, rpm: the speed at which the four rotors give `thrust_to_weight`
    /// times the weight (21 703 rpm for the Crazyflie 2.x).
    pub fn max_rpm(&self) -> f64 {
        (self.thrust_to_weight * self.weight() / (4.0 * self.kf)).sqrt()
    }

    /// Maximum total thrust of the four rotors, N (0.595 N for the Crazyflie 2.x).
    pub fn max_thrust(&self) -> f64 {
        self.thrust_to_weight * self.weight()
    }

    /// Maximum thrust of one rotor, N.
    pub fn max_motor_thrust(&self) -> f64 {
        self.max_thrust() / 4.0
    }

    /// Largest roll (or pitch) torque, N·m: the two rotors on one side at full thrust, the two
    /// on the other stopped, each acting at arm/√2 from the axis.
    pub fn max_roll_pitch_torque(&self) -> f64 {
        2.0 * self.max_motor_thrust() * self.arm / std::f64::consts::SQRT_2
    }

    /// Largest yaw torque, N·m: the two rotors spinning one way at full speed, the other two
    /// stopped.
    pub fn max_yaw_torque(&self) -> f64 {
        2.0 * self.km * self.max_rpm().powi(2)
    }
}

/// `xml` parsed as XML whose root element is `<robot>`, or the error naming what it is instead.
pub(crate) fn document<'input>(
    xml: &'input str,
    file: &str,
) -> Result<roxmltree::Document<'input>, UrdfError> {
    let doc = roxmltree::Document::parse(xml).map_err(|e| UrdfError::Xml {
        file: file.to_string(),
        message: e.to_string(),
    })?;
    let root = doc.root_element();
    if root.tag_name().name() != "robot" {
        return Err(UrdfError::Structure {
            file: file.to_string(),
            message: format!(
                "the root element is <{}>, expected <robot>",
                root.tag_name().name()
            ),
        });
    }
    Ok(doc)
}

/// The links and joints of `xml` (whose parsed `root` is its `<robot>` element) as `urdf-rs`
/// reads them; where `urdf-rs` refuses, the error names the element and value at fault.
pub(crate) fn parse_robot(
    xml: &str,
    root: &roxmltree::Node,
    file: &str,
) -> Result<urdf_rs::Robot, UrdfError> {
    urdf_rs::read_from_string(xml).map_err(|e| {
        // urdf-rs messages name neither the element nor the value; find them ourselves.
        diagnose(root, file).unwrap_or_else(|| UrdfError::Structure {
            file: file.to_string(),
            message: e.to_string(),
        })
    })
}

/// The coefficients of the `<properties>` element.
struct Properties {
    arm: f64,
    kf: f64,
    km: f64,
    thrust_to_weight: f64,
    max_speed_kmh: f64,
    ground_effect: f64,
    prop_radius: f64,
    drag_xy: f64,
    drag_z: f64,
}

impl Properties {
    fn read(root: &roxmltree::Node, file: &str) -> Result<Self, UrdfError> {
        let element = root
            .children()
            .find(|n| n.has_tag_name("properties"))
            .ok_or_else(|| UrdfError::Missing {
                file: file.to_string(),
                what: "<properties> element".to_string(),
            })?;
        let attribute = |name: &str, requirement: Requirement| -> Result<f64, UrdfError> {
            let field = format!("<properties> attribute '{name}'");
            let text = element.attribute(name).ok_or_else(|| UrdfError::Missing {
                file: file.to_string(),
                what: field.clone(),
            })?;
            let invalid = |requirement: &'static str| UrdfError::Invalid {
                file: file.to_string(),
                field: field.clone(),
                requirement,
                value: text.to_string(),
            };
            let value: f64 = text
                .trim()
                .parse()
                .map_err(|_| invalid("a finite number"))?;
            if !value.is_finite() {
                return Err(invalid("a finite number"));
            }
            match requirement {
                Requirement::Positive if value <= 0.0 => Err(invalid("a positive number")),
                Requirement::NonNegative if value < 0.0 => Err(invalid("a non-negative number")),
                Requirement::AboveOne if value <= 1.0 => {
                    Err(invalid("greater than 1 (the robot must be able to hover)"))
                }
                _ => Ok(value),
            }
        };
        Ok(Self {
            arm: attribute("arm", Requirement::Positive)?,
            kf: attribute("kf", Requirement::Positive)?,
            km: attribute("km", Requirement::Positive)?,
            thrust_to_weight: attribute("thrust2weight", Requirement::AboveOne)?,
            max_speed_kmh: attribute("max_speed_kmh", Requirement::Positive)?,
            ground_effect: attribute("gnd_eff_coeff", Requirement::NonNegative)?,
            prop_radius: attribute("prop_radius", Requirement::Positive)?,
            drag_xy: attribute("drag_coeff_xy", Requirement::NonNegative)?,
            drag_z: attribute("drag_coeff_z", Requirement::NonNegative)?,
        })
    }
}

/// The range a numeric attribute must lie in.
#[derive(Clone, Copy)]
enum Requirement {
    Positive,
    NonNegative,
    AboveOne,
}

/// `value` if it is finite and positive, else an [`UrdfError::Invalid`] naming `field`.
pub(crate) fn positive(value: f64, field: &str, file: &str) -> Result<f64, UrdfError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(UrdfError::Invalid {
            file: file.to_string(),
            field: field.to_string(),
            requirement: "a positive number",
            value: value.to_string(),
        })
    }
}

/// `value` if it is finite and not negative, else an [`UrdfError::Invalid`] naming `field`.
pub(crate) fn non_negative(value: f64, field: &str, file: &str) -> Result<f64, UrdfError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(UrdfError::Invalid {
            file: file.to_string(),
            field: field.to_string(),
            requirement: "a non-negative number",
            value: value.to_string(),
        })
    }
}

/// The first missing or non-numeric value among the link elements `urdf-rs` needs (inertial
/// mass and moments, geometry dimensions, origins), as a precise error; `None` when they all
/// look right and the problem lies elsewhere.
fn diagnose(root: &roxmltree::Node, file: &str) -> Option<UrdfError> {
    let missing = |what: String| UrdfError::Missing {
        file: file.to_string(),
        what,
    };
    // The numbers in an attribute: `count` of them, or the error naming it.
    let numbers = |node: &roxmltree::Node, attr: &str, count: usize, field: String| {
        let Some(text) = node.attribute(attr) else {
            return Some(missing(format!("{field} '{attr}'")));
        };
        let parsed: Vec<Option<f64>> = text.split_whitespace().map(|t| t.parse().ok()).collect();
        if parsed.len() != count || parsed.iter().any(Option::is_none) {
            return Some(UrdfError::Invalid {
                file: file.to_string(),
                field: format!("{field} '{attr}'"),
                requirement: if count == 1 {
                    "a number"
                } else {
                    "three numbers"
                },
                value: text.to_string(),
            });
        }
        None
    };
    for link in root.children().filter(|n| n.has_tag_name("link")) {
        let name = format!("link '{}'", link.attribute("name").unwrap_or("?"));
        if let Some(inertial) = element(&link, "inertial") {
            let Some(mass) = element(&inertial, "mass") else {
                return Some(missing(format!("{name} <inertial> <mass>")));
            };
            if let Some(e) = numbers(&mass, "value", 1, format!("{name} <mass>")) {
                return Some(e);
            }
            let Some(inertia) = element(&inertial, "inertia") else {
                return Some(missing(format!("{name} <inertial> <inertia>")));
            };
            for attr in ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"] {
                if let Some(e) = numbers(&inertia, attr, 1, format!("{name} <inertia>")) {
                    return Some(e);
                }
            }
        }
        for part in link
            .children()
            .filter(|c| c.has_tag_name("visual") || c.has_tag_name("collision"))
        {
            let tag = part.tag_name().name();
            if let Some(origin) = element(&part, "origin") {
                for attr in ["xyz", "rpy"] {
                    if origin.has_attribute(attr) {
                        let field = format!("{name} <{tag}> <origin>");
                        if let Some(e) = numbers(&origin, attr, 3, field) {
                            return Some(e);
                        }
                    }
                }
            }
            let Some(geometry) = element(&part, "geometry") else {
                return Some(missing(format!("{name} <{tag}> <geometry>")));
            };
            for shape in geometry.children().filter(roxmltree::Node::is_element) {
                let field = format!("{name} <{tag}> <{}>", shape.tag_name().name());
                let attrs: &[(&str, usize)] = match shape.tag_name().name() {
                    "cylinder" | "capsule" => &[("radius", 1), ("length", 1)],
                    "sphere" => &[("radius", 1)],
                    "box" => &[("size", 3)],
                    _ => &[],
                };
                for &(attr, count) in attrs {
                    if let Some(e) = numbers(&shape, attr, count, field.clone()) {
                        return Some(e);
                    }
                }
            }
        }
    }
    None
}

/// The first child element of `node` named `tag`.
pub(crate) fn element<'a, 'input>(
    node: &roxmltree::Node<'a, 'input>,
    tag: &str,
) -> Option<roxmltree::Node<'a, 'input>> {
    node.children().find(|c| c.has_tag_name(tag))
}

/// The one link that is no joint's child: the rigid body that flies (or drives).
pub(crate) fn base_link<'a>(
    robot: &'a urdf_rs::Robot,
    file: &str,
) -> Result<&'a urdf_rs::Link, UrdfError> {
    let roots: Vec<&urdf_rs::Link> = robot
        .links
        .iter()
        .filter(|link| !robot.joints.iter().any(|j| j.child.link == link.name))
        .collect();
    match roots.as_slice() {
        [base] => Ok(base),
        [] if robot.links.is_empty() => Err(UrdfError::Missing {
            file: file.to_string(),
            what: "<link> element".to_string(),
        }),
        _ => Err(UrdfError::Structure {
            file: file.to_string(),
            message: format!(
                "expected exactly one root link (a link that is no joint's child), found {}",
                roots.len()
            ),
        }),
    }
}

/// Horizontal radius and vertical extent of the base link's collision geometry, in the link
/// frame: each shape's horizontal reach (its offset from the z axis plus its half-width) and its
/// vertical span. Shapes tilted by roll or pitch count with their bounding sphere; meshes are
/// skipped.
fn collision_extent(base: &urdf_rs::Link, file: &str) -> Result<(f64, f64), UrdfError> {
    let mut radius: f64 = 0.0;
    let mut top = f64::NEG_INFINITY;
    let mut bottom = f64::INFINITY;
    for (index, collision) in base.collision.iter().enumerate() {
        let dim = |value: f64, name: &str| {
            positive(
                value,
                &format!("link '{}' <collision> #{} '{name}'", base.name, index + 1),
                file,
            )
        };
        // (horizontal half-width, vertical half-height, bounding-sphere radius)
        let (half_width, half_height, sphere) = match &collision.geometry {
            urdf_rs::Geometry::Cylinder { radius, length } => {
                let (r, h) = (dim(*radius, "radius")?, dim(*length, "length")? / 2.0);
                (r, h, r.hypot(h))
            }
            urdf_rs::Geometry::Capsule { radius, length } => {
                let (r, h) = (dim(*radius, "radius")?, dim(*length, "length")? / 2.0);
                (r, h + r, h + r)
            }
            urdf_rs::Geometry::Sphere { radius } => {
                let r = dim(*radius, "radius")?;
                (r, r, r)
            }
            urdf_rs::Geometry::Box { size } => {
                let [x, y, z] = size.0;
                let (x, y, z) = (dim(x, "size")?, dim(y, "size")?, dim(z, "size")?);
                (x.hypot(y) / 2.0, z / 2.0, x.hypot(y).hypot(z) / 2.0)
            }
            urdf_rs::Geometry::Mesh { .. } => continue,
        };
        let [x, y, z] = collision.origin.xyz.0;
        let [roll, pitch, _] = collision.origin.rpy.0;
        let tilted = roll.abs() > 1e-9 || pitch.abs() > 1e-9;
        let (half_width, half_height) = if tilted {
            (sphere, sphere)
        } else {
            (half_width, half_height)
        };
        radius = radius.max(x.hypot(y) + half_width);
        top = top.max(z + half_height);
        bottom = bottom.min(z - half_height);
    }
    if top < bottom {
        return Err(UrdfError::NoCollision {
            file: file.to_string(),
            link: base.name.clone(),
        });
    }
    Ok((radius, top - bottom))
}
