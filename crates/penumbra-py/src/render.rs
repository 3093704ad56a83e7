//! One render call from Python: the file's settings changed by the caller's, the library's
//! render on a thread of its own with the GIL released, and the calling thread polling for
//! Ctrl-C (`Python::check_signals`) and reporting progress every [`POLL`] until it ends.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use numpy::ndarray::{Array2, Array3};
use numpy::IntoPyArray;
use penumbra::{
    render, render_with_aovs, Aov, AovFilm, AovValues, Film, Pass, PixelBounds, RenderError,
    RenderOptions, RenderSettings, Sampler, SettingsPatch, View, World,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::camera::CameraSpec;
use crate::errors::{no_memory, render_error};

/// How often the calling thread checks for signals and reports progress while a render runs.
const POLL: Duration = Duration::from_millis(20);

/// An explicit pinhole camera as Python passes it: position, look_at, up, vertical fov in
/// degrees.
pub type CameraArgs = ([f32; 3], [f32; 3], [f32; 3], f32);

/// The keyword arguments of a render call. Python has checked their types; `None` is the
/// same as absent.
const KEYWORDS: [&str; 14] = [
    "camera",
    "alpha",
    "spp",
    "sampler",
    "light_samples",
    "seed",
    "width",
    "height",
    "region",
    "threads",
    "progress",
    "passes",
    "aovs",
    "stats",
];

/// One render call: the settings it changes and how to run it.
pub struct Request<'py> {
    /// Applied to the scene file's settings.
    pub patch: SettingsPatch,
    pub region: Option<PixelBounds>,
    pub threads: usize,
    pub progress: Option<Bound<'py, PyAny>>,
    /// Called with (samples per pixel so far, image) after each pass but the last of a
    /// progressive render; `None` renders in one pass.
    pub passes: Option<Bound<'py, PyAny>>,
    /// The AOVs asked for, in the order asked (repeats are one key of the result).
    pub aovs: Vec<Aov>,
    /// A dict to fill with the render's counts and time, when given.
    pub stats: Option<Bound<'py, PyDict>>,
    /// The camera's `[camera]` table (JSON), when the camera is given as one: built on the
    /// film rendered.
    pub table: Option<String>,
}

impl<'py> Request<'py> {
    /// The request `Scene.render`'s keyword arguments make. Names are checked in this order:
    /// the AOVs, the sampler, the camera.
    pub fn from_kwargs(kwargs: Option<&Bound<'py, PyDict>>) -> PyResult<Request<'py>> {
        for key in kwargs.iter().flat_map(|d| d.keys()) {
            let key: String = key.extract()?;
            if !KEYWORDS.contains(&key.as_str()) {
                return Err(PyTypeError::new_err(format!(
                    "render got an unexpected keyword argument {key:?}"
                )));
            }
        }
        // The value of a keyword; None when absent or None.
        let item = |key: &str| -> PyResult<Option<Bound<'py, PyAny>>> {
            match kwargs {
                Some(d) => Ok(d.get_item(key)?.filter(|v| !v.is_none())),
                None => Ok(None),
            }
        };
        let aovs: Vec<String> = item("aovs")?
            .map(|v| v.extract())
            .transpose()?
            .unwrap_or_default();
        let aovs = aovs
            .iter()
            .map(|name| {
                name.parse::<Aov>().map_err(|e| {
                    PyValueError::new_err(format!(
                        "unknown AOV {name:?} (the AOVs are: {})",
                        e.known.join(", ")
                    ))
                })
            })
            .collect::<PyResult<_>>()?;
        let sampler = match item("sampler")? {
            Some(v) => Some(
                v.extract::<String>()?
                    .parse::<Sampler>()
                    .map_err(|e| PyValueError::new_err(e.to_string()))?,
            ),
            None => None,
        };
        let mut table = None;
        let view = match item("camera")? {
            None => None,
            Some(v) => Some(match v.extract::<String>() {
                Ok(name) => View::Named(name),
                Err(_) => match v.extract::<CameraSpec>()? {
                    // A table's K counts the pixels of the film rendered: built once the
                    // film is known (see `Request::settings`).
                    CameraSpec::Table((json,)) => {
                        table = Some(json);
                        View::First
                    }
                    spec => View::Camera(spec.camera((1, 1))?),
                },
            }),
        };
        let region: Option<(u32, u32, u32, u32)> =
            item("region")?.map(|v| v.extract()).transpose()?;
        Ok(Request {
            patch: SettingsPatch {
                view,
                width: item("width")?.map(|v| v.extract()).transpose()?,
                height: item("height")?.map(|v| v.extract()).transpose()?,
                sampler,
                spp: item("spp")?.map(|v| v.extract()).transpose()?,
                light_samples: item("light_samples")?.map(|v| v.extract()).transpose()?,
                seed: item("seed")?.map(|v| v.extract()).transpose()?,
                alpha: item("alpha")?.map(|v| v.extract()).transpose()?,
                ..SettingsPatch::default()
            },
            region: region.map(|(x0, x1, y0, y1)| PixelBounds { x0, x1, y0, y1 }),
            threads: item("threads")?
                .map(|v| v.extract())
                .transpose()?
                .unwrap_or(0),
            progress: item("progress")?,
            passes: item("passes")?,
            aovs,
            stats: item("stats")?
                .map(|v| v.cast_into::<PyDict>())
                .transpose()?,
            table,
        })
    }

    /// The scene file's settings `base` (with its `render.samples`, `file_samples`) changed
    /// as this request says, the camera of a table built on their film.
    pub fn settings(
        &self,
        base: &RenderSettings,
        file_samples: Option<u32>,
    ) -> PyResult<RenderSettings> {
        let mut settings = (self.patch)
            .apply(base, file_samples)
            .map_err(|e| render_error(RenderError::Settings(e)))?;
        if let Some(table) = &self.table {
            let spec = CameraSpec::Table((table.clone(),));
            settings.view = View::Camera(spec.camera((settings.width, settings.height))?);
        }
        Ok(settings)
    }
}

/// What the render thread hands back.
type Rendered = Result<(Film, Option<AovFilm>, penumbra::RenderStats), penumbra::RenderError>;

/// Renders `world` with the scene file's settings `base` (and its `render.samples`,
/// `file_samples`) changed as the request says; returns the image, or `(image, aovs)` when
/// AOVs were asked for.
pub fn render_scene<'py>(
    py: Python<'py>,
    world: &World,
    base: &RenderSettings,
    file_samples: Option<u32>,
    r: Request<'py>,
) -> PyResult<Bound<'py, PyAny>> {
    let settings = r.settings(base, file_samples)?;
    let cancel = AtomicBool::new(false);
    let done = AtomicU64::new(0);
    let total = AtomicU64::new(0);
    let report = |d: u64, t: u64| {
        done.fetch_max(d, Ordering::Relaxed);
        total.store(t, Ordering::Relaxed);
    };
    // Finished passes wait here for the calling thread, which holds the GIL, to show them.
    let finished: std::sync::Mutex<Vec<(u32, Film)>> = std::sync::Mutex::new(Vec::new());
    let keep = |pass: &Pass| {
        let mut list = finished.lock().unwrap_or_else(|e| e.into_inner());
        list.push((pass.samples, pass.film.clone()));
    };
    let options = RenderOptions {
        threads: r.threads,
        region: r.region,
        cancel: Some(&cancel),
        progress: Some(&report),
        tiles: None,
        passes: r.passes.is_some().then_some(&keep as _),
    };
    let with_aovs = !r.aovs.is_empty();

    let result: PyResult<Rendered> = std::thread::scope(|scope| {
        let (tx, rx) = mpsc::channel::<Rendered>();
        let (settings, options) = (&settings, &options);
        let worker = scope.spawn(move || {
            let out = if with_aovs {
                render_with_aovs(world, settings, options).map(|(f, a, st)| (f, Some(a), st))
            } else {
                render(world, settings, options).map(|(f, st)| (f, None, st))
            };
            // The receiver only goes away after this thread is joined.
            let _ = tx.send(out);
        });
        // A receiver is not `Sync`: the mutex lets the GIL-free closure borrow it.
        let rx = std::sync::Mutex::new(rx);
        let mut reported = 0;
        let outcome = loop {
            let received = py.detach(|| match rx.lock() {
                Ok(rx) => rx.recv_timeout(POLL),
                Err(_) => Err(mpsc::RecvTimeoutError::Disconnected),
            });
            let mut step = || -> PyResult<()> {
                py.check_signals()?;
                if let Some(callback) = &r.progress {
                    let (d, t) = (done.load(Ordering::Relaxed), total.load(Ordering::Relaxed));
                    if d != reported && t > 0 {
                        reported = d;
                        callback.call1((d, t))?;
                    }
                }
                if let Some(callback) = &r.passes {
                    let ready =
                        std::mem::take(&mut *finished.lock().unwrap_or_else(|e| e.into_inner()));
                    for (samples, film) in ready {
                        callback.call1((samples, image_array(py, film)?))?;
                    }
                }
                Ok(())
            };
            match received {
                Ok(out) => break step().map(|()| out),
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if let Err(e) = step() {
                        cancel.store(true, Ordering::Relaxed);
                        break Err(e);
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    break Err(PyValueError::new_err(
                        "the render thread ended without a result",
                    ))
                }
            }
        };
        // Workers stop at their next row once cancelled; wait without holding the GIL.
        py.detach(|| worker.join())
            .map_err(|_| pyo3::exceptions::PyRuntimeError::new_err("the render thread panicked"))?;
        outcome
    });
    let (film, aovs, stats) = result?.map_err(render_error)?;
    if let Some(d) = &r.stats {
        d.set_item("camera_rays", stats.camera_rays)?;
        d.set_item("shadow_rays", stats.shadow_rays)?;
        d.set_item("seconds", stats.time.as_secs_f64())?;
        d.set_item("rays_per_second", stats.rays_per_second())?;
        d.set_item("threads", stats.threads)?;
    }
    let image = image_array(py, film)?;
    match aovs {
        None => Ok(image.into_any()),
        Some(aovs) => {
            let dict = aov_dict(py, &aovs, &r.aovs)?;
            Ok(PyTuple::new(py, [image.into_any(), dict.into_any()])?.into_any())
        }
    }
}

/// The channels of `pixels` in order, in the same memory: a pixel and an `[f32; 3]` have one
/// size and alignment, so the standard library collects them in place, and a film as large
/// as memory allows needs no second copy to become an array.
fn floats(pixels: Vec<penumbra::Rgb>) -> Vec<f32> {
    let arrays: Vec<[f32; 3]> = pixels.into_iter().map(|p| p.to_array()).collect();
    arrays.into_flattened()
}

/// An (H, W, 3) float32 array of a film's pixels, row 0 at the top; (H, W, 4) with its
/// alpha (premultiplied RGBA).
fn image_array(py: Python<'_>, film: Film) -> PyResult<Bound<'_, PyAny>> {
    let (w, h) = (film.width as usize, film.height as usize);
    let err = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
    let array = match &film.alpha {
        None => Array3::from_shape_vec((h, w, 3), floats(film.pixels)).map_err(err)?,
        Some(alpha) => {
            let what = format!("the {w}x{h} result arrays");
            let mut data = crate::errors::buffer("Scene.render", &what, w * h * 4)?;
            let rgba = film.pixels.iter().zip(alpha);
            data.extend(rgba.flat_map(|(p, &a)| p.extend(a).to_array()));
            Array3::from_shape_vec((h, w, 4), data).map_err(err)?
        }
    };
    Ok(array.into_pyarray(py).into_any())
}

/// The requested AOVs as a dict of arrays: (H, W) float32 depth, (H, W, 3) float32 normal,
/// albedo and position, (H, W) uint32 ids.
fn aov_dict<'py>(py: Python<'py>, aovs: &AovFilm, asked: &[Aov]) -> PyResult<Bound<'py, PyDict>> {
    let (w, h) = (aovs.width as usize, aovs.height as usize);
    let err = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
    let dict = PyDict::new(py);
    for &aov in asked {
        let values = aovs
            .values(aov)
            .map_err(|_| no_memory("Scene.render", &format!("the {w}x{h} result arrays")))?;
        let value = match (values, aov.components()) {
            (AovValues::Floats(v), 1) => Array2::from_shape_vec((h, w), v)
                .map_err(err)?
                .into_pyarray(py)
                .into_any(),
            (AovValues::Floats(v), n) => Array3::from_shape_vec((h, w, n), v)
                .map_err(err)?
                .into_pyarray(py)
                .into_any(),
            (AovValues::Ids(v), _) => Array2::from_shape_vec((h, w), v)
                .map_err(err)?
                .into_pyarray(py)
                .into_any(),
        };
        dict.set_item(aov.name(), value)?;
    }
    Ok(dict)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_film_becomes_floats_in_its_own_memory() {
        let pixels: Vec<penumbra::Rgb> = (0..1000)
            .map(|i| penumbra::Rgb::new(i as f32, 0.5, -1.0))
            .collect();
        let at = pixels.as_ptr() as usize;
        let data = floats(pixels);
        assert_eq!(data.as_ptr() as usize, at, "the pixels were copied");
        assert_eq!(data.len(), 3000);
        assert_eq!(&data[3..6], &[1.0, 0.5, -1.0]);
    }
}
