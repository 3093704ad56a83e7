//! What belongs to one render call rather than to the world: the camera (by name or an explicit
//! pinhole), film size, sampler and samples per pixel, light samples, seed and shading model.
//! A scene file supplies defaults for all of them; a caller changes any per call.

use std::str::FromStr;

use thiserror::Error;

use crate::camera::{Camera, FRAMING_CAMERA};
use crate::integrator::{LightModel, Shading, ShadingSettings};
use crate::math::Rgb;
use crate::names::{escape_controls, parse_name, UnknownName};
use crate::sampling::{nearest_squares, perfect_square_root, Sampler};
use crate::world::World;

/// Largest film: 2^28 pixels (16384 × 16384), 3 GiB of float RGB.
pub const MAX_PIXELS: u64 = 1 << 28;
/// Largest area-light grid resolution N.
pub const MAX_LIGHT_SAMPLES: u32 = 1024;
/// Largest samples per pixel.
pub const MAX_SPP: u32 = 1 << 16;

/// Which camera a render looks through.
// A camera with a lens model is a few hundred bytes; a render holds one View.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, Default, PartialEq)]
pub enum View {
    /// The world's first camera.
    #[default]
    First,
    /// The world's camera of this name; `auto` ([`FRAMING_CAMERA`]), when the world has no
    /// camera of that name, is the camera framing the world's bounds ([`Camera::framing`]).
    Named(String),
    /// An explicit camera, whether or not the world has it.
    Camera(Camera),
}

/// The settings of one render. `Default` gives the scene format's defaults (rgss, 4 samples
/// per pixel, each light's own N, seed 0, Phong, ambient 0.1, black background) on a 640×480
/// film through the first camera.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// The camera.
    pub view: View,
    /// Film width in pixels.
    pub width: u32,
    /// Film height in pixels.
    pub height: u32,
    /// Pixel sample pattern.
    pub sampler: Sampler,
    /// Samples per pixel: a perfect square, 1 for [`Sampler::Center`].
    pub spp: u32,
    /// N of every area light (N×N samples), replacing each light's own; `None` keeps them.
    pub light_samples: Option<u32>,
    /// Seed of every random choice.
    pub seed: u64,
    /// Specular lobe.
    pub shading: Shading,
    /// Light model.
    pub light_model: LightModel,
    /// Ambient light I_a.
    pub ambient: Rgb,
    /// Radiance of camera rays that hit nothing.
    pub background: Rgb,
    /// Coverage alpha (Cycles' transparent film): the film gets the fraction of each pixel's
    /// samples whose camera ray hits geometry ([`Film::alpha`](crate::Film::alpha)), and what
    /// camera rays miss (the background, a visible environment) adds nothing to the colour,
    /// which is then premultiplied by the alpha. Environments still light the scene.
    pub alpha: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            view: View::First,
            width: 640,
            height: 480,
            sampler: Sampler::Rgss,
            spp: 4,
            light_samples: None,
            seed: 0,
            shading: Shading::Phong,
            light_model: LightModel::Phong,
            ambient: Rgb::splat(0.1),
            background: Rgb::ZERO,
            alpha: false,
        }
    }
}

/// Why settings cannot be rendered. Messages name the setting, never a command-line flag.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum SettingsError {
    /// Samples per pixel is not a perfect square in range.
    #[error(
        "samples per pixel must be a perfect square (1, 4, 9, 16, ...) up to {MAX_SPP}, not {0}{nearest}",
        nearest = nearest_squares(*.0 as i64, MAX_SPP)
    )]
    Spp(u32),
    /// The center sampler with more than one sample.
    #[error("the center sampler takes exactly 1 sample")]
    CenterSpp,
    /// Light samples N out of range.
    #[error("light samples N must be between 1 and {MAX_LIGHT_SAMPLES}, not {0}")]
    LightSamples(u32),
    /// A film without pixels.
    #[error("the film must be at least 1x1 pixels, not {width}x{height}")]
    EmptyFilm {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
    },
    /// A film too large for memory.
    #[error("a {width}x{height} image is too large for memory (at most {MAX_PIXELS} pixels)")]
    FilmTooLarge {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
    },
    /// No camera of that name.
    #[error(
        "no camera named \"{}\" (the scene has: {})",
        escape_controls(name),
        escape_controls(known)
    )]
    UnknownCamera {
        /// The name asked for.
        name: String,
        /// The names there are, comma-separated.
        known: String,
    },
    /// The world has no camera and none was given.
    #[error("the scene has no camera; give one")]
    NoCamera,
}

impl RenderSettings {
    /// Samples per pixel along each axis (n of the n×n pattern).
    pub fn samples_per_axis(&self) -> u32 {
        perfect_square_root(self.spp).unwrap_or(1)
    }

    /// Checks every setting and returns the camera to look through.
    pub fn check(&self, world: &World) -> Result<Camera, SettingsError> {
        self.check_values()?;
        self.view.camera(world)
    }

    /// Checks every setting but the view, which only a world can check: film size, samples
    /// per pixel against the sampler, light samples. [`RenderSettings::check`] checks these
    /// first, in this order.
    pub fn check_values(&self) -> Result<(), SettingsError> {
        let (width, height) = (self.width, self.height);
        if width == 0 || height == 0 {
            return Err(SettingsError::EmptyFilm { width, height });
        }
        if width as u64 * height as u64 > MAX_PIXELS {
            return Err(SettingsError::FilmTooLarge { width, height });
        }
        if self.spp > MAX_SPP || perfect_square_root(self.spp).is_none() {
            return Err(SettingsError::Spp(self.spp));
        }
        if self.sampler == Sampler::Center && self.spp != 1 {
            return Err(SettingsError::CenterSpp);
        }
        if let Some(n) = self.light_samples {
            if !(1..=MAX_LIGHT_SAMPLES).contains(&n) {
                return Err(SettingsError::LightSamples(n));
            }
        }
        Ok(())
    }

    /// What the integrator needs of these settings.
    pub(crate) fn shading_settings(&self) -> ShadingSettings {
        ShadingSettings {
            shading: self.shading,
            light_model: self.light_model,
            ambient: self.ambient,
            light_samples: self.light_samples,
        }
    }
}

impl View {
    /// The camera this view looks through in `world`.
    pub fn camera(&self, world: &World) -> Result<Camera, SettingsError> {
        match self {
            View::Camera(camera) => Ok(*camera),
            View::First => world
                .cameras()
                .first()
                .map(|(_, c)| *c)
                .ok_or(SettingsError::NoCamera),
            View::Named(name) => world
                .camera(name)
                .copied()
                .or_else(|| framing(name, world))
                .ok_or_else(|| {
                    let known: Vec<&str> =
                        world.cameras().iter().map(|(n, _)| n.as_str()).collect();
                    SettingsError::UnknownCamera {
                        name: name.clone(),
                        known: known.join(", "),
                    }
                }),
        }
    }
}

/// The framing camera of `world` when `name` asks for it ([`FRAMING_CAMERA`]).
fn framing(name: &str, world: &World) -> Option<Camera> {
    (name == FRAMING_CAMERA).then(|| Camera::framing(world.bounds()))?
}

// The names of the shading choices, as scene files spell them (`render.shading`,
// `render.light_model`); the integrator owns the types, the settings their names.
impl Shading {
    /// Both lobes, in the order messages list them.
    pub const ALL: [Shading; 2] = [Shading::Phong, Shading::BlinnPhong];

    /// Its name in scene files: "phong" or "blinn-phong"; [`str::parse`] takes it back.
    pub fn name(self) -> &'static str {
        match self {
            Shading::Phong => "phong",
            Shading::BlinnPhong => "blinn-phong",
        }
    }
}

impl FromStr for Shading {
    type Err = UnknownName;

    fn from_str(name: &str) -> Result<Shading, UnknownName> {
        parse_name("shading", name, &Shading::ALL, Shading::name)
    }
}

impl LightModel {
    /// Both models, in the order messages list them.
    pub const ALL: [LightModel; 2] = [LightModel::Phong, LightModel::Physical];

    /// Its name in scene files: "phong" or "physical"; [`str::parse`] takes it back.
    pub fn name(self) -> &'static str {
        match self {
            LightModel::Phong => "phong",
            LightModel::Physical => "physical",
        }
    }
}

impl FromStr for LightModel {
    type Err = UnknownName;

    fn from_str(name: &str) -> Result<LightModel, UnknownName> {
        parse_name("light model", name, &LightModel::ALL, LightModel::name)
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::world::WorldBuilder;

    fn world() -> World {
        let mut b = WorldBuilder::new();
        let cam = |z: f32| Camera::new(Vec3::new(0.0, 0.0, z), Vec3::ZERO, Vec3::Y, 40.0).unwrap();
        b.add_camera("near", cam(2.0)).unwrap();
        b.add_camera("far", cam(9.0)).unwrap();
        b.build(1)
    }

    #[test]
    fn the_view_picks_a_camera() {
        let w = world();
        let s = RenderSettings::default();
        assert_eq!(s.check(&w).unwrap().position().z, 2.0);
        let s = RenderSettings {
            view: View::Named("far".into()),
            ..s
        };
        assert_eq!(s.check(&w).unwrap().position().z, 9.0);
        let s = RenderSettings {
            view: View::Named("mid".into()),
            ..s
        };
        assert_eq!(
            s.check(&w),
            Err(SettingsError::UnknownCamera {
                name: "mid".into(),
                known: "near, far".into()
            })
        );
        let empty = WorldBuilder::new().build(1);
        assert_eq!(
            RenderSettings::default().check(&empty),
            Err(SettingsError::NoCamera)
        );
    }

    #[test]
    fn bad_numbers_are_refused() {
        let w = world();
        let with = |f: fn(&mut RenderSettings)| {
            let mut s = RenderSettings::default();
            f(&mut s);
            s.check(&w).map(|_| ())
        };
        assert_eq!(with(|s| s.spp = 3), Err(SettingsError::Spp(3)));
        assert_eq!(with(|s| s.spp = 0), Err(SettingsError::Spp(0)));
        assert_eq!(
            with(|s| s.sampler = Sampler::Center),
            Err(SettingsError::CenterSpp)
        );
        assert_eq!(
            with(|s| s.light_samples = Some(0)),
            Err(SettingsError::LightSamples(0))
        );
        assert!(matches!(
            with(|s| s.width = 0),
            Err(SettingsError::EmptyFilm { .. })
        ));
        assert!(matches!(
            with(|s| (s.width, s.height) = (100_000, 100_000)),
            Err(SettingsError::FilmTooLarge { .. })
        ));
        assert_eq!(with(|s| s.spp = 16), Ok(()));
    }

    #[test]
    fn shading_names_round_trip_as_scene_files_spell_them() {
        for s in Shading::ALL {
            assert_eq!(s.name().parse::<Shading>(), Ok(s));
            // The scene file's reader (serde) knows each by the same name.
            let quoted = format!("\"{}\"", s.name());
            assert_eq!(serde_json::from_str::<Shading>(&quoted).unwrap(), s);
        }
        for m in LightModel::ALL {
            assert_eq!(m.name().parse::<LightModel>(), Ok(m));
            let quoted = format!("\"{}\"", m.name());
            assert_eq!(serde_json::from_str::<LightModel>(&quoted).unwrap(), m);
        }
        let e = "blinn".parse::<Shading>().unwrap_err();
        assert_eq!(
            e.to_string(),
            r#"unknown shading "blinn" (use "phong" or "blinn-phong")"#
        );
        let e = "pbr".parse::<LightModel>().unwrap_err();
        assert_eq!(
            e.to_string(),
            r#"unknown light model "pbr" (use "phong" or "physical")"#
        );
    }
}
