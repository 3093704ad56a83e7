//! The scene file's types, mirroring SPEC §2 one to one. TOML and JSON files deserialize into
//! these; nothing here is validated beyond types, finiteness and unknown keys (see `build`).
//!
//! ```
//! let scene = penumbra::SceneFile::from_str(r#"
//! [film]
//! width = 64
//! height = 48
//!
//! [camera]
//! position = [0, 1, 5]
//! look_at = [0, 0, 0]
//! fov = 45
//!
//! [materials.red]
//! diffuse = [0.8, 0.1, 0.1]
//!
//! [[lights]]
//! type = "point"
//! position = [0, 5, 5]
//!
//! [[objects]]
//! type = "cube"
//! material = "red"
//! center = [0, 0, 0]
//! size = 1
//! rotate = [0, 30, 0]
//! "#, penumbra::SceneFormat::Toml, "inline.toml", ".").unwrap();
//! assert_eq!(scene.desc.film.width, 64);
//! ```

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

/// A vector `[x, y, z]` of finite numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec3Desc(pub [f64; 3]);

impl<'de> Deserialize<'de> for Vec3Desc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let [x, y, z] = <[Num; 3]>::deserialize(d)?;
        Ok(Vec3Desc([x.0, y.0, z.0]))
    }
}

/// A pair `[s, t]` of finite numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec2Desc(pub [f64; 2]);

impl<'de> Deserialize<'de> for Vec2Desc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let [x, y] = <[Num; 2]>::deserialize(d)?;
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

/// The whole scene file.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    /// Image size and output.
    pub film: FilmDesc,
    /// The single camera (exclusive with `cameras`).
    pub camera: Option<CameraDesc>,
    /// Named cameras (exclusive with `camera`).
    #[serde(default)]
    pub cameras: Named<CameraDesc>,
    /// Sampling and shading settings.
    #[serde(default)]
    pub render: RenderDesc,
    /// Named materials.
    #[serde(default)]
    pub materials: Named<MaterialDesc>,
    /// Named textures.
    #[serde(default)]
    pub textures: Named<TextureDesc>,
    /// Lights.
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    /// Objects.
    #[serde(default)]
    pub objects: Vec<ObjectDesc>,
}

/// `[film]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FilmDesc {
    /// Width in pixels (≥ 1).
    pub width: i64,
    /// Height in pixels (≥ 1).
    pub height: i64,
    /// Output path, relative to the scene file's folder.
    pub output: Option<String>,
    /// Plain power-law encoding `c^(1/gamma)` instead of the sRGB curve.
    pub gamma: Option<Num>,
}

/// `[camera]` or `[cameras.NAME]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// Eye position.
    pub position: Vec3Desc,
    /// The point seen at the film's center.
    pub look_at: Vec3Desc,
    /// Up direction (default +y).
    pub up: Option<Vec3Desc>,
    /// Vertical field of view in degrees, in (0, 180).
    pub fov: Num,
}

/// `[render]`.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RenderDesc {
    /// "center" | "grid" | "rgss" | "jittered" (default "rgss").
    pub sampler: Option<String>,
    /// Samples per pixel, a perfect square (default 4; 1 for "center").
    pub samples: Option<i64>,
    /// Default N of area lights (default 5).
    pub light_samples: Option<i64>,
    /// "phong" | "blinn-phong" (default "phong").
    pub shading: Option<String>,
    /// "phong" | "physical" (default "phong").
    pub light_model: Option<String>,
    /// Ambient light I_a (default 0.1).
    pub ambient: Option<ColorDesc>,
    /// Radiance of camera rays that miss (default 0).
    pub background: Option<ColorDesc>,
    /// Seed of every random choice (default 0).
    pub seed: Option<u64>,
}

/// `[materials.NAME]`.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// k_d (default 0.8).
    pub diffuse: Option<ColorDesc>,
    /// k_a (default: k_d).
    pub ambient: Option<ColorDesc>,
    /// k_s (default 0).
    pub specular: Option<ColorDesc>,
    /// Phong exponent p ≥ 0 (default 16).
    pub shininess: Option<Num>,
    /// Name of a texture multiplying k_a and k_d.
    pub texture: Option<String>,
}

/// `[textures.NAME]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TextureDesc {
    /// "image" or "checker".
    #[serde(rename = "type")]
    pub kind: TextureType,
    /// Image file (image textures).
    pub file: Option<String>,
    /// "bilinear" (default) | "nearest".
    pub filter: Option<String>,
    /// "repeat" (default) | "clamp".
    pub wrap: Option<String>,
    /// "srgb" (default) | "linear".
    pub colorspace: Option<String>,
    /// Default [1, 1].
    pub uv_scale: Option<Vec2Desc>,
    /// Default [0, 0].
    pub uv_offset: Option<Vec2Desc>,
    /// Checker color where the square index sum is even (default 1).
    pub even: Option<ColorDesc>,
    /// Checker color elsewhere (default 0).
    pub odd: Option<ColorDesc>,
    /// Checker squares per unit of uv (default 8).
    pub checks: Option<Num>,
}

/// Texture kinds.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum TextureType {
    /// An image file.
    Image,
    /// The procedural checkerboard.
    Checker,
}

/// `[[lights]]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    /// "area" or "point".
    #[serde(rename = "type")]
    pub kind: LightType,
    /// Area light center.
    pub center: Option<Vec3Desc>,
    /// Area light first edge.
    pub u: Option<Vec3Desc>,
    /// Area light second edge.
    pub v: Option<Vec3Desc>,
    /// Point light position.
    pub position: Option<Vec3Desc>,
    /// Color (default 1).
    pub color: Option<ColorDesc>,
    /// Scale of the color (default 1).
    pub intensity: Option<Num>,
    /// Area light N (default render.light_samples).
    pub samples: Option<i64>,
    /// Area light: random point per cell.
    pub jitter: Option<bool>,
}

/// Light kinds.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum LightType {
    /// Parallelogram area light.
    Area,
    /// Point light.
    Point,
}

/// `[[objects]]`: one flat table for every type; `build` checks which keys each type takes.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    /// The object's type.
    #[serde(rename = "type")]
    pub kind: ObjectType,
    /// Material name (default: the format's default material).
    pub material: Option<String>,
    /// Triangle vertices.
    pub vertices: Option<[Vec3Desc; 3]>,
    /// Triangle uvs.
    pub uvs: Option<[Vec2Desc; 3]>,
    /// Triangle vertex normals.
    pub normals: Option<[Vec3Desc; 3]>,
    /// Quad corner.
    pub corner: Option<Vec3Desc>,
    /// Quad first edge.
    pub u: Option<Vec3Desc>,
    /// Quad second edge.
    pub v: Option<Vec3Desc>,
    /// Cube or sphere center.
    pub center: Option<Vec3Desc>,
    /// Cube edge length(s).
    pub size: Option<ColorDesc>,
    /// Sphere radius.
    pub radius: Option<Num>,
    /// Mesh file (Wavefront OBJ).
    pub file: Option<String>,
    /// Scale factor(s).
    pub scale: Option<ColorDesc>,
    /// Rotation about x, y, z in degrees.
    pub rotate: Option<Vec3Desc>,
    /// Translation.
    pub translate: Option<Vec3Desc>,
}

/// Object kinds.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum ObjectType {
    /// One triangle.
    Triangle,
    /// A parallelogram.
    Quad,
    /// A box.
    Cube,
    /// A tessellated sphere.
    Sphere,
    /// A Wavefront OBJ file.
    Mesh,
}

impl ObjectType {
    /// The name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            ObjectType::Triangle => "triangle",
            ObjectType::Quad => "quad",
            ObjectType::Cube => "cube",
            ObjectType::Sphere => "sphere",
            ObjectType::Mesh => "mesh",
        }
    }
}
