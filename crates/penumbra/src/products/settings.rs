//! What an image depends on, as its record keeps it: [`RecordSettings`], written by name
//! (serde with named fields, every `f32` to the bit), so that a record reads the same in any
//! version that writes the same settings, and a record of other settings (or of an older
//! layout, such as the Debug text earlier versions wrote) simply does not match: its image
//! is rendered again.
//!
//! ```
//! use penumbra::products::{CameraRecord, RenderRecord};
//! use penumbra::{RenderSettings, View};
//!
//! let settings = RenderSettings { view: View::Named("high".into()), spp: 16, ..Default::default() };
//! let record = RenderRecord::of(&settings);
//! assert_eq!(record.camera, CameraRecord::Named("high".into()));
//! let text = serde_json::to_string(&record)?;
//! assert!(text.starts_with(r#"{"camera":{"named":"high"},"width":640,"height":480,"sampler":"rgss","spp":16,"#));
//! assert_eq!(serde_json::from_str::<RenderRecord>(&text)?, record);
//! # Ok::<(), serde_json::Error>(())
//! ```

use serde::{Deserialize, Serialize};

use super::frames::LensFields;
use crate::pose::{CameraPose, Mat3Rows};
use crate::render::{RenderSettings, View};

/// The settings of an image's record (its `settings` key): what `--resume` and Python's
/// batches compare to decide that an image is done.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordSettings {
    /// penumbra's version.
    pub penumbra: String,
    /// The scene's digest ([`SceneFile::digest`](crate::SceneFile::digest)).
    pub scene_digest: String,
    /// The scene camera's name; `None` for an explicit camera.
    pub camera: Option<String>,
    /// The frame of a path camera; `None` for a still camera.
    pub frame: Option<i64>,
    /// The resolved render settings.
    pub render: RenderRecord,
    /// The region rendered, `[x0, x1, y0, y1]`; `None` for the whole film.
    pub region: Option<[u32; 4]>,
    /// The AOV names written, in order.
    pub aovs: Vec<String>,
    /// The film's gamma; `None` for the sRGB curve.
    pub gamma: Option<f32>,
    /// The image format's name (`png`, `jpg`, `exr`, `pfm`).
    pub format: String,
}

/// [`RenderSettings`] by name, every number to the bit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderRecord {
    /// The camera.
    pub camera: CameraRecord,
    /// Film width in pixels.
    pub width: u32,
    /// Film height in pixels.
    pub height: u32,
    /// The sampler's name.
    pub sampler: String,
    /// Samples per pixel.
    pub spp: u32,
    /// N of every area light, `None` for each light's own.
    pub light_samples: Option<u32>,
    /// The seed.
    pub seed: u64,
    /// The specular lobe's name.
    pub shading: String,
    /// The light model's name.
    pub light_model: String,
    /// Ambient light, linear RGB.
    pub ambient: [f32; 3],
    /// Background radiance, linear RGB.
    pub background: [f32; 3],
    /// Coverage alpha (absent from records written before it: false).
    #[serde(default)]
    pub alpha: bool,
}

/// The camera of [`RenderRecord`]: `"first"`, `{"named": NAME}`, `{"pinhole": {...}}` or
/// `{"explicit": {...}}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum CameraRecord {
    /// The world's first camera.
    First,
    /// The world's camera of this name.
    Named(String),
    /// An explicit pinhole camera.
    Pinhole {
        /// The eye.
        position: [f32; 3],
        /// The point looked at.
        look_at: [f32; 3],
        /// The up direction.
        up: [f32; 3],
        /// Vertical field of view in degrees.
        fov: f32,
    },
    /// An explicit camera with K, a lens model or an aperture: its pinhole keys (the fov
    /// unused where K or the model sets the field of view), its K on the film and its lens.
    Explicit {
        /// The eye.
        position: [f32; 3],
        /// The point looked at.
        look_at: [f32; 3],
        /// The up direction.
        up: [f32; 3],
        /// Vertical field of view in degrees.
        fov: f32,
        /// K on the film, as `--poses` writes it.
        #[serde(rename = "K")]
        k: Mat3Rows,
        /// The lens model and its coefficients, as `--poses` writes them.
        lens: LensFields,
    },
}

impl RenderRecord {
    /// The record of `settings`.
    pub fn of(settings: &RenderSettings) -> RenderRecord {
        let camera = match &settings.view {
            View::First => CameraRecord::First,
            View::Named(name) => CameraRecord::Named(name.clone()),
            View::Camera(c) if c.sees_by_fov() => CameraRecord::Pinhole {
                position: c.position().to_array(),
                look_at: c.look_at().to_array(),
                up: c.up().to_array(),
                fov: c.fov_y_deg(),
            },
            View::Camera(c) => {
                let pose = CameraPose::new(c, settings.width, settings.height, (0, 0));
                CameraRecord::Explicit {
                    position: c.position().to_array(),
                    look_at: c.look_at().to_array(),
                    up: c.up().to_array(),
                    fov: c.fov_y_deg(),
                    k: pose.k,
                    lens: LensFields::of(&pose),
                }
            }
        };
        RenderRecord {
            camera,
            width: settings.width,
            height: settings.height,
            sampler: settings.sampler.name().to_owned(),
            spp: settings.spp,
            light_samples: settings.light_samples,
            seed: settings.seed,
            shading: settings.shading.name().to_owned(),
            light_model: settings.light_model.name().to_owned(),
            ambient: settings.ambient.to_array(),
            background: settings.background.to_array(),
            alpha: settings.alpha,
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::Camera;

    #[test]
    fn every_number_reads_back_to_the_same_bits() {
        let camera = Camera::new(
            Vec3::new(0.1, 1.0 / 3.0, -7.25e-8),
            Vec3::ZERO,
            Vec3::Y,
            33.3,
        )
        .unwrap();
        let settings = RenderSettings {
            view: View::Camera(camera),
            seed: u64::MAX,
            light_samples: Some(3),
            ..Default::default()
        };
        let record = RenderRecord::of(&settings);
        let text = serde_json::to_string(&record).unwrap();
        let back: RenderRecord = serde_json::from_str(&text).unwrap();
        assert_eq!(back, record);
        let CameraRecord::Pinhole { position, fov, .. } = back.camera else {
            panic!("{text}")
        };
        assert_eq!(
            position.map(f32::to_bits),
            camera.position().to_array().map(f32::to_bits)
        );
        assert_eq!(fov.to_bits(), 33.3f32.to_bits());
        // Through a JSON value too (what a record read back compares).
        let value: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(
            serde_json::from_value::<RenderRecord>(value).unwrap(),
            record
        );
    }

    #[test]
    fn the_debug_text_of_earlier_records_is_no_settings() {
        let old = r#""RenderSettings { view: First, width: 640 }""#;
        assert!(serde_json::from_str::<RenderRecord>(old).is_err());
    }
}
