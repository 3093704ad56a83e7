//! The scene file's types, mirroring SPEC §2 (docs/spec.md) one to one. TOML and JSON files
//! deserialize into these. Parsing checks types, finiteness, option names and which keys each
//! table (and each kind of object, light and texture) takes; ranges and cross-references are
//! checked when the scene is built (see `build`).
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

mod cameras;
mod lights;
mod objects;
mod tagged;
mod textures;
mod values;

use serde::Deserialize;

pub use cameras::{
    ApertureDesc, CameraDesc, CameraKeyDesc, CameraPathDesc, LensDesc, ModelDesc, OpticsDesc,
    PathType, PoseDesc, StillCameraDesc,
};
pub use lights::{
    AreaLightDesc, DirectionalLightDesc, EnvironmentLightDesc, LightDesc, LightType,
    PointLightDesc, SpotLightDesc,
};
pub use objects::{
    CubeDesc, InstancesDesc, Matrix, MeshDesc, ObjectDesc, ObjectType, PlacementDesc, QuadDesc,
    ShapeDesc, SphereDesc, TransformsDesc, TriangleDesc,
};
pub use textures::{
    CheckerTextureDesc, ColorSpace, ImageTextureDesc, TextureDesc, TextureKindDesc, TextureType,
};
pub use values::{ColorDesc, Named, Num, Vec2Desc, Vec3Desc};

use crate::integrator::{LightModel, Shading};
use crate::sampling::Sampler;

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
    /// Coverage alpha: an RGBA image, what camera rays miss transparent (default false).
    pub alpha: Option<bool>,
}

/// `[render]`.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RenderDesc {
    /// "center" | "grid" | "rgss" | "jittered" (default "rgss").
    pub sampler: Option<Sampler>,
    /// Samples per pixel, a perfect square (default 4; 1 for "center").
    pub samples: Option<i64>,
    /// Default N of area lights (default 5).
    pub light_samples: Option<i64>,
    /// "phong" | "blinn-phong" (default "phong").
    pub shading: Option<Shading>,
    /// "phong" | "physical" (default "phong").
    pub light_model: Option<LightModel>,
    /// Ambient light I_a (default 0.1).
    pub ambient: Option<ColorDesc>,
    /// Radiance of camera rays that miss (default 0).
    pub background: Option<ColorDesc>,
    /// Seed of every random choice (default 0): an integer, or a string of decimal digits for
    /// seeds above TOML's largest integer (2^63 − 1), up to 2^64 − 1 as `--seed` takes them.
    #[serde(default, deserialize_with = "values::seed")]
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
    /// Cut-out alpha factor in [0, 1] (default 1); any of the three `alpha` keys makes the
    /// material a cut-out.
    pub alpha: Option<Num>,
    /// Name of a texture whose alpha channel (its luminance without one) multiplies `alpha`.
    pub alpha_texture: Option<String>,
    /// The least alpha kept, in [0, 1] (default 0.5).
    pub alpha_cutoff: Option<Num>,
}
