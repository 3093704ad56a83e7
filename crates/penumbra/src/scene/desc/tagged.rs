//! Tables whose `type` key decides which other keys they take (`[[objects]]`, `[[lights]]`,
//! `[textures.NAME]`), read key by key so that every error keeps its key path and location.
//!
//! serde's internally tagged enums would buffer the table before choosing the variant, losing
//! both, and `flatten` does not combine with `deny_unknown_fields`; this small visitor reads
//! each value straight from the file instead. A key that the table's kind does not take is
//! rejected while its value is read, so the message points at that key. (When `type` comes
//! after such a key, the key can only be reported at the table.)

use std::fmt;
use std::marker::PhantomData;

use serde::de::{self, DeserializeSeed, Deserializer, MapAccess, Visitor};
use serde::Deserialize;

/// A table read by [`TaggedVisitor`]: a `type` key, keys every kind takes, and keys of its kind.
pub(super) trait Tagged: Sized {
    /// The values of the `type` key.
    type Kind: Copy + 'static + for<'de> Deserialize<'de>;
    /// Storage for the value of every key any kind takes.
    type Fields: Default;
    /// Keys every kind takes, besides `type`.
    const COMMON: &'static [&'static str];
    /// Every kind-specific key of any kind.
    const ALL: &'static [&'static str];
    /// Every kind, as the hint for a key met before `type` lists them.
    const KINDS: &'static [Self::Kind];
    /// The kind-specific keys of `kind`.
    fn keys(kind: Self::Kind) -> &'static [&'static str];
    /// How a message names a table of `kind` ("a cube").
    fn describe(kind: Self::Kind) -> &'static str;
    /// Reads the value of `key`, one of [`Tagged::COMMON`] or [`Tagged::ALL`], into `fields`.
    fn read<'de, A: MapAccess<'de>>(
        fields: &mut Self::Fields,
        key: &str,
        map: &mut A,
    ) -> Result<(), A::Error>;
    /// The table once every key is read, or the name of a required key that is missing.
    fn finish(kind: Self::Kind, fields: Self::Fields) -> Result<Self, &'static str>;
}

/// Deserializes a [`Tagged`] table.
pub(super) fn deserialize<'de, T: Tagged, D: Deserializer<'de>>(d: D) -> Result<T, D::Error> {
    d.deserialize_map(TaggedVisitor::<T>(PhantomData))
}

fn takes<T: Tagged>(kind: T::Kind, key: &str) -> bool {
    T::keys(kind).contains(&key) || T::COMMON.contains(&key)
}

/// The keys a table of `kind` takes besides `type`: its own, then those every kind takes.
fn key_list<T: Tagged>(kind: T::Kind) -> String {
    let keys: Vec<&str> = T::keys(kind).iter().chain(T::COMMON).copied().collect();
    keys.join(", ")
}

/// The message for `key`, which a table of `kind` does not take; with the kind not yet known
/// (the key comes before `type`), the keys of every kind.
fn unknown_key<T: Tagged>(kind: Option<T::Kind>, key: &str) -> String {
    match kind {
        Some(kind) => format!(
            "unknown key `{key}` for {} (it takes: {})",
            T::describe(kind),
            key_list::<T>(kind)
        ),
        None => {
            let kinds: Vec<String> = T::KINDS
                .iter()
                .map(|&k| format!("{} takes: {}", T::describe(k), key_list::<T>(k)))
                .collect();
            format!("unknown key `{key}` ({})", kinds.join("; "))
        }
    }
}

struct TaggedVisitor<T>(PhantomData<T>);

impl<'de, T: Tagged> Visitor<'de> for TaggedVisitor<T> {
    type Value = T;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a table with a `type` key")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<T, A::Error> {
        let mut kind: Option<T::Kind> = None;
        let mut fields = T::Fields::default();
        let mut seen: Vec<String> = Vec::new();
        while let Some(key) = map.next_key::<String>()? {
            if seen.contains(&key) {
                return reject(&mut map, format!("duplicate key `{key}`"));
            }
            if key == "type" {
                let k: T::Kind = map.next_value()?;
                if let Some(bad) = seen.iter().find(|s| !takes::<T>(k, s)) {
                    return Err(de::Error::custom(unknown_key::<T>(Some(k), bad)));
                }
                kind = Some(k);
            } else if !(T::ALL.contains(&key.as_str()) || T::COMMON.contains(&key.as_str()))
                || kind.is_some_and(|k| !takes::<T>(k, &key))
            {
                return reject(&mut map, unknown_key::<T>(kind, &key));
            } else {
                T::read(&mut fields, &key, &mut map)?;
            }
            seen.push(key);
        }
        let kind = kind.ok_or_else(|| de::Error::custom("missing key `type`"))?;
        T::finish(kind, fields).map_err(|key| de::Error::custom(format!("missing key `{key}`")))
    }
}

/// Fails with `message` while the current key's value is read, so that the error carries the
/// key's path and the value's position.
fn reject<'de, A: MapAccess<'de>, T>(map: &mut A, message: String) -> Result<T, A::Error> {
    map.next_value_seed(Reject(message.clone()))?;
    Err(de::Error::custom(message))
}

struct Reject(String);

impl<'de> DeserializeSeed<'de> for Reject {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        // Through the deserializer, so that it attaches the value's span to the error.
        d.deserialize_any(self)
    }
}

impl Reject {
    fn fail<E: de::Error>(self) -> Result<(), E> {
        Err(E::custom(self.0))
    }
}

impl<'de> Visitor<'de> for Reject {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(&self.0)
    }
    fn visit_bool<E: de::Error>(self, _: bool) -> Result<(), E> {
        self.fail()
    }
    fn visit_i64<E: de::Error>(self, _: i64) -> Result<(), E> {
        self.fail()
    }
    fn visit_u64<E: de::Error>(self, _: u64) -> Result<(), E> {
        self.fail()
    }
    fn visit_f64<E: de::Error>(self, _: f64) -> Result<(), E> {
        self.fail()
    }
    fn visit_str<E: de::Error>(self, _: &str) -> Result<(), E> {
        self.fail()
    }
    fn visit_unit<E: de::Error>(self) -> Result<(), E> {
        self.fail()
    }
    fn visit_none<E: de::Error>(self) -> Result<(), E> {
        self.fail()
    }
    fn visit_seq<A: de::SeqAccess<'de>>(self, _: A) -> Result<(), A::Error> {
        self.fail()
    }
    fn visit_map<A: MapAccess<'de>>(self, _: A) -> Result<(), A::Error> {
        self.fail()
    }
}
