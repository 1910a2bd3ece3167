//! Serde of [`PartialSettings`]: a scene file's `[render]` table, each value read as written
//! ([`Written`]) and put through [`PartialSettings::set`], so that a value of the wrong kind
//! is told as `render.radius: expected a length in metres (0.01) or pixel footprints
//! ("0.2px"), found a boolean` rather than in serde's terms (`data did not match any variant
//! of untagged enum`, `expected u32`). The error is raised while the value is being read, so
//! a format that tracks positions (TOML) places it at the value.

use std::fmt;

use serde::Deserialize;
use serde::de::{self, DeserializeSeed, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};

use crate::PartialSettings;
use crate::values::{RENDER_KEYS, Written};

impl<'de> Deserialize<'de> for PartialSettings {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_map(Table)
    }
}

impl<'de> Deserialize<'de> for Written {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(AsWritten)
    }
}

/// The `[render]` table, key by key; an unknown key is refused with the list of keys.
struct Table;

impl<'de> Visitor<'de> for Table {
    type Value = PartialSettings;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("the [render] table")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<PartialSettings, A::Error> {
        let mut out = PartialSettings::default();
        while let Some(key) = map.next_key_seed(Key)? {
            map.next_value_seed(Field {
                key,
                into: &mut out,
            })?;
        }
        Ok(out)
    }
}

/// A key of the table, refused while it is read (so that TOML places the error at the key)
/// unless it is one of [`RENDER_KEYS`].
struct Key;

impl<'de> DeserializeSeed<'de> for Key {
    type Value = &'static str;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<&'static str, D::Error> {
        d.deserialize_str(self)
    }
}

impl<'de> Visitor<'de> for Key {
    type Value = &'static str;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a key of the [render] table")
    }

    fn visit_str<E: de::Error>(self, v: &str) -> Result<&'static str, E> {
        RENDER_KEYS
            .iter()
            .find(|k| **k == v)
            .copied()
            .ok_or_else(|| E::unknown_field(v, RENDER_KEYS))
    }
}

/// One key's value, put into the settings as it is read.
struct Field<'a> {
    key: &'a str,
    into: &'a mut PartialSettings,
}

impl Field<'_> {
    fn put<E: de::Error>(self, value: Written) -> Result<(), E> {
        self.into
            .set(self.key, &value)
            .map_err(|e| E::custom(format!("render.{}: {}", e.field, e.message)))
    }
}

impl<'de> DeserializeSeed<'de> for Field<'_> {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

/// Implements the scalar `visit_*` methods of a visitor by turning the value into [`Written`]
/// and handing it to `$put`.
macro_rules! scalars {
    ($put:ident) => {
        fn visit_bool<E: de::Error>(self, v: bool) -> Result<Self::Value, E> {
            self.$put(Written::Bool(v))
        }
        fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
            self.$put(Written::Whole(v.into()))
        }
        fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
            self.$put(Written::Whole(v.into()))
        }
        fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
            self.$put(Written::Number(v))
        }
        fn visit_str<E: de::Error>(self, v: &str) -> Result<Self::Value, E> {
            self.$put(Written::Text(v.to_string()))
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
            let mut list = Vec::new();
            while let Some(v) = seq.next_element::<Written>()? {
                list.push(v);
            }
            self.$put(Written::List(list))
        }
        fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
            while map.next_entry::<IgnoredAny, IgnoredAny>()?.is_some() {}
            self.$put(Written::Table)
        }
    };
}

impl<'de> Visitor<'de> for Field<'_> {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "a value of render.{}", self.key)
    }

    scalars!(put);
}

/// Any value, as written.
struct AsWritten;

impl AsWritten {
    fn keep<E>(self, v: Written) -> Result<Written, E> {
        Ok(v)
    }
}

impl<'de> Visitor<'de> for AsWritten {
    type Value = Written;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a value")
    }

    scalars!(keep);
}
