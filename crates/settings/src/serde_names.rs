//! Serde of the named settings (mode, noise model, sampler) as their names, for
//! `#[serde(with = "serde_names")]` on the fields of [`crate::RenderSettings`]. An unknown
//! name is refused with the message that lists the names ([`crate::SettingsError::UnknownName`]).

use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serializer};

use crate::{Named, parse_name};

/// Writes the value's name (its `Display`).
pub(crate) fn serialize<T: Named, S: Serializer>(value: &T, s: S) -> Result<S::Ok, S::Error> {
    s.collect_str(value)
}

/// Reads a name.
pub(crate) fn deserialize<'de, T: Named, D: Deserializer<'de>>(d: D) -> Result<T, D::Error> {
    let name = String::deserialize(d)?;
    parse_name(&name).map_err(D::Error::custom)
}
