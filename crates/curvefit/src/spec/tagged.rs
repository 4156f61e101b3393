//! The objects with a `"type"` — `constraint`, `tangents[i]` and `boundary` — read as one flat
//! object of all their types' fields, then checked against the type it names.
//!
//! serde reads an internally tagged enum by buffering the whole object before it knows the
//! variant, and reads the variant from that buffer, where the field path is no longer tracked:
//! `"constraint": {"type": "balls", "radii": 0.1}` was refused as "constraint: must be an array
//! (a value inside constraint, …)", and a wrong half-space offset six levels down the same way.
//! A type without fields also let every other field through unread: `{"type": "interpolate",
//! "radii": [...]}` interpolated, and the radii were ignored without a word. Read flat, every
//! error has its full path (`constraint.radii`, `constraint.sets[0][1].offset`) and a field that
//! does not belong to the type is refused.
//!
//! No field name has two meanings across the types of one object (`radius` is a number in each
//! tangent and boundary type that has one), so one flat struct per object reads every type.
//! serde's own wording is kept for the messages (`missing field`, `unknown field`), which
//! [`super::messages::rewrite`] puts in the user's words.

use std::fmt;
use std::marker::PhantomData;

use serde::de::value::MapAccessDeserializer;
use serde::de::{Deserializer, Error, MapAccess, Visitor};
use serde::Deserialize;

use super::refine_types::{BoundarySpec, ConstraintSpec, HalfSpaceSpec, TangentSpec};

/// Reads the struct `T` from a JSON object only (a derived struct also reads an array, its
/// fields by position: `"constraint": [1, 2]` was read as a type of `1`); `what` names the
/// object for the message of anything else.
fn object<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
    de: D,
    what: &'static str,
) -> Result<T, D::Error> {
    struct Object<T>(&'static str, PhantomData<T>);
    impl<'de, T: Deserialize<'de>> Visitor<'de> for Object<T> {
        type Value = T;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            // ("struct …" is what `messages` recognizes as "an object", the field's own form.)
            write!(f, "struct {}", self.0)
        }
        fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
            // The map access is the path tracker's, so the fields' paths are kept.
            T::deserialize(MapAccessDeserializer::new(map))
        }
    }
    de.deserialize_map(Object(what, PhantomData))
}

/// The value of a field the type needs.
fn need<T, E: Error>(value: Option<T>, name: &'static str) -> Result<T, E> {
    value.ok_or_else(|| E::missing_field(name))
}

/// Refuses the first field given (`present`: each name and whether it was given) that the type
/// does not have (`fields`).
fn only<E: Error>(
    present: &[(&'static str, bool)],
    fields: &'static [&'static str],
) -> Result<(), E> {
    match present
        .iter()
        .find(|(name, given)| *given && !fields.contains(name))
    {
        Some((name, _)) => Err(E::unknown_field(name, fields)),
        None => Ok(()),
    }
}

#[derive(Deserialize)]
#[serde(rename_all = "snake_case")]
enum ConstraintType {
    Interpolate,
    Balls,
    Smoothing,
    Halfspaces,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ConstraintFields {
    #[serde(rename = "type")]
    kind: ConstraintType,
    radii: Option<Vec<f64>>,
    weights: Option<Vec<f64>>,
    sets: Option<Vec<Vec<HalfSpaceSpec>>>,
}

impl<'de> Deserialize<'de> for ConstraintSpec {
    fn deserialize<D: Deserializer<'de>>(de: D) -> Result<Self, D::Error> {
        let f: ConstraintFields = object(de, "ConstraintSpec")?;
        let present = [
            ("radii", f.radii.is_some()),
            ("weights", f.weights.is_some()),
            ("sets", f.sets.is_some()),
        ];
        Ok(match f.kind {
            ConstraintType::Interpolate => {
                only(&present, &[])?;
                ConstraintSpec::Interpolate
            }
            ConstraintType::Balls => {
                only(&present, &["radii"])?;
                ConstraintSpec::Balls {
                    radii: need(f.radii, "radii")?,
                }
            }
            ConstraintType::Smoothing => {
                only(&present, &["weights"])?;
                ConstraintSpec::Smoothing {
                    weights: need(f.weights, "weights")?,
                }
            }
            ConstraintType::Halfspaces => {
                only(&present, &["sets"])?;
                ConstraintSpec::Halfspaces {
                    sets: need(f.sets, "sets")?,
                }
            }
        })
    }
}

#[derive(Deserialize)]
#[serde(rename_all = "snake_case")]
enum TangentType {
    Ball,
    Wedge,
    Tension,
    Halfspaces,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TangentFields {
    #[serde(rename = "type")]
    kind: TangentType,
    center: Option<Vec<f64>>,
    radius: Option<f64>,
    direction: Option<Vec<f64>>,
    half_angle: Option<f64>,
    halfspaces: Option<Vec<HalfSpaceSpec>>,
}

impl<'de> Deserialize<'de> for TangentSpec {
    fn deserialize<D: Deserializer<'de>>(de: D) -> Result<Self, D::Error> {
        let f: TangentFields = object(de, "TangentSpec")?;
        let present = [
            ("center", f.center.is_some()),
            ("radius", f.radius.is_some()),
            ("direction", f.direction.is_some()),
            ("half_angle", f.half_angle.is_some()),
            ("halfspaces", f.halfspaces.is_some()),
        ];
        Ok(match f.kind {
            TangentType::Ball => {
                only(&present, &["center", "radius"])?;
                TangentSpec::Ball {
                    center: need(f.center, "center")?,
                    radius: need(f.radius, "radius")?,
                }
            }
            TangentType::Wedge => {
                only(&present, &["direction", "half_angle"])?;
                TangentSpec::Wedge {
                    direction: need(f.direction, "direction")?,
                    half_angle: need(f.half_angle, "half_angle")?,
                }
            }
            TangentType::Tension => {
                only(&present, &["radius"])?;
                TangentSpec::Tension {
                    radius: need(f.radius, "radius")?,
                }
            }
            TangentType::Halfspaces => {
                only(&present, &["halfspaces"])?;
                TangentSpec::Halfspaces {
                    halfspaces: need(f.halfspaces, "halfspaces")?,
                }
            }
        })
    }
}

#[derive(Deserialize)]
#[serde(rename_all = "snake_case")]
enum BoundaryType {
    Natural,
    Clamped,
    NearClamped,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoundaryFields {
    #[serde(rename = "type")]
    kind: BoundaryType,
    start: Option<Vec<f64>>,
    end: Option<Vec<f64>>,
    radius: Option<f64>,
}

impl<'de> Deserialize<'de> for BoundarySpec {
    fn deserialize<D: Deserializer<'de>>(de: D) -> Result<Self, D::Error> {
        let f: BoundaryFields = object(de, "BoundarySpec")?;
        let present = [
            ("start", f.start.is_some()),
            ("end", f.end.is_some()),
            ("radius", f.radius.is_some()),
        ];
        Ok(match f.kind {
            BoundaryType::Natural => {
                only(&present, &[])?;
                BoundarySpec::Natural
            }
            BoundaryType::Clamped => {
                only(&present, &["start", "end"])?;
                BoundarySpec::Clamped {
                    start: need(f.start, "start")?,
                    end: need(f.end, "end")?,
                }
            }
            BoundaryType::NearClamped => {
                only(&present, &["start", "end", "radius"])?;
                BoundarySpec::NearClamped {
                    start: need(f.start, "start")?,
                    end: need(f.end, "end")?,
                    radius: need(f.radius, "radius")?,
                }
            }
        })
    }
}
