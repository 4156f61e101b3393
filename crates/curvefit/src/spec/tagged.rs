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

/// One object with a `"type"`: `$spec`'s Deserialize through the flat struct `$fields` of every
/// field (each optional) and the enum `$types` of the type names, then per type the fields it
/// has, in order (a field of another type refused, a missing one required). The type names are
/// the variants' own, in snake_case as `$spec` is written.
macro_rules! tagged {
    (
        $spec:ident via $fields:ident, $types:ident {
            $($field:ident: $ty:ty),* $(,)?
        }
        $($variant:ident { $($has:ident),* }),* $(,)?
    ) => {
        #[derive(Deserialize)]
        #[serde(rename_all = "snake_case")]
        enum $types {
            $($variant),*
        }

        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct $fields {
            #[serde(rename = "type")]
            kind: $types,
            $($field: Option<$ty>,)*
        }

        impl<'de> Deserialize<'de> for $spec {
            fn deserialize<D: Deserializer<'de>>(de: D) -> Result<Self, D::Error> {
                let f: $fields = object(de, stringify!($spec))?;
                let present = [$((stringify!($field), f.$field.is_some())),*];
                Ok(match f.kind {
                    $($types::$variant => {
                        only(&present, &[$(stringify!($has)),*])?;
                        $spec::$variant {
                            $($has: need(f.$has, stringify!($has))?),*
                        }
                    })*
                })
            }
        }
    };
}

tagged! {
    ConstraintSpec via ConstraintFields, ConstraintType {
        radii: Vec<f64>,
        weights: Vec<f64>,
        sets: Vec<Vec<HalfSpaceSpec>>,
    }
    Interpolate {},
    Balls { radii },
    Smoothing { weights },
    Halfspaces { sets },
}

tagged! {
    TangentSpec via TangentFields, TangentType {
        center: Vec<f64>,
        radius: f64,
        direction: Vec<f64>,
        half_angle: f64,
        halfspaces: Vec<HalfSpaceSpec>,
    }
    Ball { center, radius },
    Wedge { direction, half_angle },
    Tension { radius },
    Halfspaces { halfspaces },
}

tagged! {
    BoundarySpec via BoundaryFields, BoundaryType {
        start: Vec<f64>,
        end: Vec<f64>,
        radius: f64,
    }
    Natural {},
    Clamped { start, end },
    NearClamped { start, end, radius },
}
