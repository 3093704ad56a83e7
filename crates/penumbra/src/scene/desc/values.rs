//! The value types of scene files: finite numbers, vectors, colors (a number or three), and
//! named tables kept in file order.

use std::fmt;

use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;

/// A finite number that fits in the renderer's 32-bit floats.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
pub struct Num(pub f64);

/// `x` when the renderer can hold it: finite and within f32's range.
fn finite<E: de::Error>(x: f64) -> Result<f64, E> {
    if !x.is_finite() {
        Err(E::custom(format!("{x} is not a finite number")))
    } else if x.abs() > f32::MAX as f64 {
        Err(E::custom(format!(
            "{x} is out of range (at most {:e} in magnitude)",
            f32::MAX
        )))
    } else {
        Ok(x)
    }
}

impl<'de> Deserialize<'de> for Num {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        finite(f64::deserialize(d)?).map(Num)
    }
}

/// A seed: a non-negative integer, or (beyond TOML's and JSON's signed 64-bit integers) a
/// string of decimal digits up to 2^64 − 1.
pub(super) fn seed<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    struct SeedVisitor;
    impl Visitor<'_> for SeedVisitor {
        type Value = u64;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str(
                "a non-negative integer up to 18446744073709551615 (a string of digits above \
                 9223372036854775807)",
            )
        }
        fn visit_u64<E: de::Error>(self, v: u64) -> Result<u64, E> {
            Ok(v)
        }
        fn visit_i64<E: de::Error>(self, v: i64) -> Result<u64, E> {
            u64::try_from(v).map_err(|_| E::invalid_value(de::Unexpected::Signed(v), &self))
        }
        fn visit_str<E: de::Error>(self, v: &str) -> Result<u64, E> {
            let digits = !v.is_empty() && v.bytes().all(|b| b.is_ascii_digit());
            digits
                .then(|| v.parse().ok())
                .flatten()
                .ok_or_else(|| E::invalid_value(de::Unexpected::Str(v), &self))
        }
    }
    d.deserialize_any(SeedVisitor).map(Some)
}

/// A vector `[x, y, z]` of finite numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec3Desc(pub [f64; 3]);

impl<'de> Deserialize<'de> for Vec3Desc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Exact([x, y, z]) = Exact::<Num, 3>::deserialize(d)?;
        Ok(Vec3Desc([x.0, y.0, z.0]))
    }
}

/// An array of exactly `N` values. serde's own `[T; N]` stops reading after `N` elements,
/// and TOML then drops the rest without a word (`position = [0, 1, 5, 6]`); this one counts
/// them all and reports an array of the wrong length either way.
pub(super) struct Exact<T, const N: usize>(pub(super) [T; N]);

impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Exact<T, N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T, const N: usize>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for V<T, N> {
            type Value = Exact<T, N>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "an array of length {N}")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Exact<T, N>, A::Error> {
                let mut items = Vec::with_capacity(N);
                while let Some(item) = seq.next_element()? {
                    if items.len() == N {
                        // Count the rest for the message without keeping them.
                        let mut len = N + 1;
                        while seq.next_element::<de::IgnoredAny>()?.is_some() {
                            len += 1;
                        }
                        return Err(de::Error::invalid_length(len, &self));
                    }
                    items.push(item);
                }
                let len = items.len();
                items
                    .try_into()
                    .map(Exact)
                    .map_err(|_| de::Error::invalid_length(len, &self))
            }
        }
        d.deserialize_seq(V::<T, N>(std::marker::PhantomData))
    }
}

/// A pair `[s, t]` of finite numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec2Desc(pub [f64; 2]);

impl<'de> Deserialize<'de> for Vec2Desc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let Exact([x, y]) = Exact::<Num, 2>::deserialize(d)?;
        Ok(Vec2Desc([x.0, y.0]))
    }
}

/// A color `[r, g, b]` or one number meaning grey; also used for "number or vector" keys such
/// as a cube's `size` and an object's `scale`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColorDesc(pub [f64; 3]);

impl<'de> Deserialize<'de> for ColorDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ColorDesc;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or an array of three numbers")
            }
            fn visit_f64<E: de::Error>(self, x: f64) -> Result<ColorDesc, E> {
                finite(x).map(|x| ColorDesc([x; 3]))
            }
            fn visit_i64<E: de::Error>(self, x: i64) -> Result<ColorDesc, E> {
                self.visit_f64(x as f64)
            }
            fn visit_u64<E: de::Error>(self, x: u64) -> Result<ColorDesc, E> {
                self.visit_f64(x as f64)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<ColorDesc, A::Error> {
                let v = Vec3Desc::deserialize(de::value::SeqAccessDeserializer::new(seq))?;
                Ok(ColorDesc(v.0))
            }
        }
        d.deserialize_any(V)
    }
}

/// Named entries in file order (`[materials.red]`, `[cameras.front]`, ...).
#[derive(Clone, Debug, PartialEq)]
pub struct Named<T>(pub Vec<(String, T)>);

impl<T> Default for Named<T> {
    fn default() -> Self {
        Named(Vec::new())
    }
}

impl<T> Named<T> {
    /// The entry called `name` and its position.
    pub fn get(&self, name: &str) -> Option<(usize, &T)> {
        self.0
            .iter()
            .enumerate()
            .find(|(_, (n, _))| n == name)
            .map(|(i, (_, t))| (i, t))
    }

    /// The names, in file order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.0.iter().map(|(n, _)| n.as_str())
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Named<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
            type Value = Named<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a table of named entries")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Named<T>, A::Error> {
                let mut out: Vec<(String, T)> = Vec::new();
                while let Some(name) = map.next_key::<String>()? {
                    if out.iter().any(|(n, _)| *n == name) {
                        return Err(de::Error::custom(format!("duplicate name `{name}`")));
                    }
                    let value = map.next_value()?;
                    out.push((name, value));
                }
                Ok(Named(out))
            }
        }
        d.deserialize_map(V(std::marker::PhantomData))
    }
}

impl Num {
    /// The value as the renderer's 32-bit float.
    pub fn f32(self) -> f32 {
        self.0 as f32
    }
}

impl Vec3Desc {
    /// The vector in 32-bit floats.
    pub fn vec3(self) -> glam::Vec3 {
        glam::Vec3::new(self.0[0] as f32, self.0[1] as f32, self.0[2] as f32)
    }
}

impl Vec2Desc {
    /// The pair in 32-bit floats.
    pub fn vec2(self) -> glam::Vec2 {
        glam::Vec2::new(self.0[0] as f32, self.0[1] as f32)
    }
}

impl ColorDesc {
    /// The color (or per-axis value) in 32-bit floats.
    pub fn rgb(self) -> glam::Vec3 {
        glam::Vec3::new(self.0[0] as f32, self.0[1] as f32, self.0[2] as f32)
    }
}
