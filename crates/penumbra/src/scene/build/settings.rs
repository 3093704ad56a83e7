//! `[film]`, `[camera]`/`[cameras.NAME]` and `[render]`: the cameras go into the world, the
//! rest becomes the scene's default [`RenderSettings`], with the library's defaults for what
//! the file leaves out.

use std::path::{Path, PathBuf};

use super::{Builder, Result};
use crate::camera::Camera;
use crate::camera_path::CameraPath;
use crate::image_format::OutputFormat;
use crate::render::{implied_spp, RenderSettings, View, MAX_LIGHT_SAMPLES, MAX_PIXELS, MAX_SPP};
use crate::sampling::{nearest_squares, perfect_square_root, Sampler};
use crate::scene::desc::{CameraDesc, Num};
use crate::scene::error::{ErrorKind, KeyPath};

/// Area-light N when neither the light nor `[render]` gives one.
const DEFAULT_LIGHT_SAMPLES: u32 = 5;

/// The checked `[film]` table.
pub(super) struct Film {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) output: Option<PathBuf>,
    pub(super) gamma: Option<f32>,
}

impl Builder<'_> {
    pub(super) fn film(&self) -> Result<Film> {
        let d = &self.file.desc.film;
        let path = KeyPath::root("film");
        let dim = |key: &str, v: i64| -> Result<u32> {
            if v < 1 {
                return Err(self.bad(
                    &path.key(key),
                    format!("{key} must be at least 1 pixel, not {v}"),
                ));
            }
            u32::try_from(v)
                .map_err(|_| self.bad(&path.key(key), format!("{key} {v} is too large")))
        };
        let width = dim("width", d.width)?;
        let height = dim("height", d.height)?;
        if width as u64 * height as u64 > MAX_PIXELS {
            let message = format!(
                "a {width}x{height} image is too large for memory (at most {MAX_PIXELS} pixels)"
            );
            return Err(self.bad(&path.key("width"), message));
        }
        let gamma = match d.gamma {
            Some(Num(g)) if g <= 0.0 => {
                return Err(self.bad(
                    &path.key("gamma"),
                    format!("gamma must be positive, not {g}"),
                ))
            }
            g => g.map(Num::f32),
        };
        let output = match d.output.as_deref() {
            None => None,
            // Checked even when the command line's -o wins: the file is wrong either way.
            Some(o) if OutputFormat::from_path(Path::new(o)).is_none() => {
                return Err(self.bad(
                    &path.key("output"),
                    format!("unknown image format \"{o}\" (use .png, .jpg, .exr or .pfm)"),
                ))
            }
            Some(o) => Some(self.reference(&path.key("output"), o, ErrorKind::BadValue)?),
        };
        Ok(Film {
            width,
            height,
            output,
            gamma,
        })
    }

    /// Every camera of the file, checked, into the world under its name (a single `[camera]`
    /// is called "camera"); returns how many. A file without one is refused unless an object
    /// imports a glTF file's cameras (checked once they are added).
    pub(super) fn cameras(&mut self) -> Result<usize> {
        let desc = &self.file.desc;
        let named: Vec<(String, &CameraDesc, KeyPath)> =
            match (&desc.camera, desc.cameras.0.is_empty()) {
                (Some(_), false) => {
                    return Err(self.bad(
                        &KeyPath::root("cameras"),
                        "a scene has either [camera] or [cameras.NAME] tables, not both",
                    ))
                }
                (None, true) if self.imports_cameras() => return Ok(0),
                (None, true) => {
                    return Err(self.err(
                        ErrorKind::MissingKey,
                        &KeyPath::default(),
                        "missing key `camera` (a [camera] table or [cameras.NAME] tables)",
                    ))
                }
                (Some(c), true) => vec![("camera".to_owned(), c, KeyPath::root("camera"))],
                (None, false) => desc
                    .cameras
                    .0
                    .iter()
                    .map(|(n, c)| (n.clone(), c, KeyPath::root("cameras").key(n)))
                    .collect(),
            };
        let count = named.len();
        for (name, c, path) in named {
            let camera = match c {
                CameraDesc::Still(c) => self.still_camera(&path, c)?,
                CameraDesc::Keys {
                    up,
                    fov,
                    keys,
                    optics,
                } => {
                    let moving = self.key_path(&path, keys, *up, *fov, optics.needs_fov())?;
                    let moving = self.path_optics(&path, moving, optics)?;
                    self.first_camera(&path, name.clone(), moving)?
                }
                CameraDesc::Path {
                    up,
                    fov,
                    path: p,
                    optics,
                } => {
                    let moving = self.kind_path(&path, p, *up, *fov)?;
                    let moving = self.path_optics(&path, moving, optics)?;
                    self.first_camera(&path, name.clone(), moving)?
                }
            };
            // Names are table keys, unique by construction.
            self.world
                .add_camera(name, camera)
                .map_err(|e| self.bad(&path, e.to_string()))?;
        }
        Ok(count)
    }

    /// A path's camera at its first frame, which the world holds under the path's name (the
    /// camera of a render of the name alone); the path is kept for the others.
    fn first_camera(&mut self, table: &KeyPath, name: String, path: CameraPath) -> Result<Camera> {
        // A checked path has a camera at each of its frames.
        let first = path
            .camera(*path.frames().start())
            .ok_or_else(|| self.bad(table, "the path has no first frame"))?;
        self.paths.push((name, path));
        Ok(first)
    }

    /// True when an object asks for a glTF file's cameras.
    fn imports_cameras(&self) -> bool {
        self.file.desc.objects.iter().any(|o| {
            matches!(&o.shape, crate::scene::desc::ShapeDesc::Mesh(m) if m.cameras == Some(true))
        })
    }

    /// The file's render settings on a `width × height` film through the first camera, and
    /// the default N of area lights.
    pub(super) fn settings(&self, width: u32, height: u32) -> Result<(RenderSettings, u32)> {
        let r = &self.file.desc.render;
        let path = KeyPath::root("render");
        let defaults = RenderSettings::default();
        let sampler = r.sampler.unwrap_or(defaults.sampler);
        let samples = match r.samples {
            None => None,
            Some(s) => Some(
                u32::try_from(s)
                    .ok()
                    .filter(|&s| s <= MAX_SPP && perfect_square_root(s).is_some())
                    .ok_or_else(|| {
                        self.bad(
                            &path.key("samples"),
                            format!(
                                "samples must be a perfect square (1, 4, 9, 16, ...) up to {MAX_SPP}, not {s}{}",
                                nearest_squares(s, MAX_SPP)
                            ),
                        )
                    })?,
            ),
        };
        let spp = match samples {
            // A sampler an override chose without a count takes its own, as `--sampler` does.
            Some(n) if !self.file.sampler_set_alone() => {
                if sampler == Sampler::Center && n != 1 {
                    return Err(self.bad(
                        &path.key("samples"),
                        "the center sampler takes exactly 1 sample",
                    ));
                }
                n
            }
            samples => implied_spp(sampler, samples),
        };
        let light_samples = match r.light_samples {
            None => DEFAULT_LIGHT_SAMPLES,
            Some(n) => self.light_n(&path.key("light_samples"), n)?,
        };
        let settings = RenderSettings {
            view: View::First,
            width,
            height,
            sampler,
            spp,
            light_samples: None,
            seed: r.seed.unwrap_or(defaults.seed),
            shading: r.shading.unwrap_or(defaults.shading),
            light_model: r.light_model.unwrap_or(defaults.light_model),
            ambient: r.ambient.map_or(defaults.ambient, |c| c.rgb()),
            background: r.background.map_or(defaults.background, |c| c.rgb()),
            alpha: self.file.desc.film.alpha.unwrap_or(defaults.alpha),
        };
        Ok((settings, light_samples))
    }

    /// An area light's N, checked.
    pub(super) fn light_n(&self, path: &KeyPath, n: i64) -> Result<u32> {
        u32::try_from(n)
            .ok()
            .filter(|&n| (1..=MAX_LIGHT_SAMPLES).contains(&n))
            .ok_or_else(|| {
                self.bad(
                    path,
                    format!("light samples N must be between 1 and {MAX_LIGHT_SAMPLES}, not {n}"),
                )
            })
    }
}
