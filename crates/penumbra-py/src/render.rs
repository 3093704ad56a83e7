//! One render call from Python: the file's settings changed by the caller's, the library's
//! render on a thread of its own with the GIL released, and the calling thread polling for
//! Ctrl-C (`Python::check_signals`) and reporting progress every [`POLL`] until it ends.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use numpy::ndarray::{Array2, Array3};
use numpy::IntoPyArray;
use penumbra::{
    render, render_with_aovs, AovFilm, Film, PixelBounds, RenderOptions, RenderSettings, Sampler,
    View, World,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::camera::camera;
use crate::errors::{buffer, render_error};

/// How often the calling thread checks for signals and reports progress while a render runs.
const POLL: Duration = Duration::from_millis(20);

/// The names of the AOVs, as `render(aovs=...)` takes them.
pub const AOV_NAMES: [&str; 6] = [
    "depth",
    "normal",
    "albedo",
    "position",
    "object_id",
    "primitive_id",
];

/// An explicit pinhole camera as Python passes it: position, look_at, up, vertical fov in
/// degrees.
pub type CameraArgs = ([f32; 3], [f32; 3], [f32; 3], f32);

/// The arguments of one render call.
pub struct Request<'py> {
    pub camera_name: Option<String>,
    pub camera: Option<CameraArgs>,
    pub spp: Option<u32>,
    pub sampler: Option<String>,
    pub light_samples: Option<u32>,
    pub seed: Option<u64>,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub region: Option<(u32, u32, u32, u32)>,
    pub threads: usize,
    pub progress: Option<Bound<'py, PyAny>>,
    pub aovs: Vec<String>,
    /// A dict to fill with the render's counts and time, when given.
    pub stats: Option<Bound<'py, PyDict>>,
}

/// The sampler of this name.
fn sampler(name: &str) -> PyResult<Sampler> {
    [
        Sampler::Center,
        Sampler::Grid,
        Sampler::Rgss,
        Sampler::Jittered,
    ]
    .into_iter()
    .find(|s| s.name() == name)
    .ok_or_else(|| {
        PyValueError::new_err(format!(
            "unknown sampler {name:?} (use \"center\", \"grid\", \"rgss\" or \"jittered\")"
        ))
    })
}

/// The file's settings with the request's applied, as the command line applies its flags: a
/// sampler without `spp` takes its own default count (1 for center, else the file's
/// `samples`, else 4).
fn settings(
    defaults: &RenderSettings,
    file_samples: Option<i64>,
    r: &Request,
) -> PyResult<RenderSettings> {
    let mut s = defaults.clone();
    if let Some(w) = r.width {
        s.width = w;
    }
    if let Some(h) = r.height {
        s.height = h;
    }
    if let Some(name) = &r.sampler {
        s.sampler = sampler(name)?;
        s.spp = match (s.sampler, file_samples) {
            (Sampler::Center, _) => 1,
            (_, Some(n)) => u32::try_from(n).unwrap_or(u32::MAX),
            (_, None) => 4,
        };
    }
    if let Some(spp) = r.spp {
        s.spp = spp;
    }
    if r.light_samples.is_some() {
        s.light_samples = r.light_samples;
    }
    if let Some(seed) = r.seed {
        s.seed = seed;
    }
    if let Some(name) = &r.camera_name {
        s.view = View::Named(name.clone());
    }
    if let Some((position, look_at, up, fov)) = r.camera {
        s.view = View::Camera(camera(position, look_at, up, fov)?);
    }
    Ok(s)
}

/// What the render thread hands back.
type Rendered = Result<(Film, Option<AovFilm>, penumbra::RenderStats), penumbra::RenderError>;

/// Renders `world` as the request says and returns the image, or `(image, aovs)` when AOVs
/// were asked for.
pub fn render_scene<'py>(
    py: Python<'py>,
    world: &World,
    defaults: &RenderSettings,
    file_samples: Option<i64>,
    r: Request<'py>,
) -> PyResult<Bound<'py, PyAny>> {
    for name in &r.aovs {
        if !AOV_NAMES.contains(&name.as_str()) {
            return Err(PyValueError::new_err(format!(
                "unknown AOV {name:?} (the AOVs are: {})",
                AOV_NAMES.join(", ")
            )));
        }
    }
    let settings = settings(defaults, file_samples, &r)?;
    let region = r
        .region
        .map(|(x0, x1, y0, y1)| PixelBounds { x0, x1, y0, y1 });
    let cancel = AtomicBool::new(false);
    let done = AtomicU64::new(0);
    let total = AtomicU64::new(0);
    let report = |d: u64, t: u64| {
        done.fetch_max(d, Ordering::Relaxed);
        total.store(t, Ordering::Relaxed);
    };
    let options = RenderOptions {
        threads: r.threads,
        region,
        cancel: Some(&cancel),
        progress: Some(&report),
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

/// A `MemoryError`-checked buffer for `len` values of the render's result, an image of
/// `w × h` pixels.
fn result_buffer<T>(len: usize, (w, h): (usize, usize)) -> PyResult<Vec<T>> {
    buffer("Scene.render", &format!("the {w}x{h} result arrays"), len)
}

/// The channels of `pixels` in order, in the same memory: a pixel and an `[f32; 3]` have one
/// size and alignment, so the standard library collects them in place, and a film as large
/// as memory allows needs no second copy to become an array.
fn floats(pixels: Vec<penumbra::Rgb>) -> Vec<f32> {
    let arrays: Vec<[f32; 3]> = pixels.into_iter().map(|p| p.to_array()).collect();
    arrays.into_flattened()
}

/// An (H, W, 3) float32 array of a film's pixels, row 0 at the top.
fn image_array(py: Python<'_>, film: Film) -> PyResult<Bound<'_, PyAny>> {
    let (w, h) = (film.width as usize, film.height as usize);
    let data = floats(film.pixels);
    let array = Array3::from_shape_vec((h, w, 3), data)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(array.into_pyarray(py).into_any())
}

/// The requested AOVs as a dict of arrays: (H, W) float32 depth, (H, W, 3) float32 normal,
/// albedo and position, (H, W) uint32 ids.
fn aov_dict<'py>(
    py: Python<'py>,
    aovs: &AovFilm,
    names: &[String],
) -> PyResult<Bound<'py, PyDict>> {
    let (w, h) = (aovs.width as usize, aovs.height as usize);
    let err = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
    let dict = PyDict::new(py);
    for name in names {
        let px = &aovs.pixels;
        let vec3 = |f: fn(&penumbra::AovPixel) -> glam::Vec3| -> PyResult<Bound<'py, PyAny>> {
            let mut data = result_buffer(w * h * 3, (w, h))?;
            data.extend(px.iter().flat_map(|p| f(p).to_array()));
            Ok(Array3::from_shape_vec((h, w, 3), data)
                .map_err(err)?
                .into_pyarray(py)
                .into_any())
        };
        let ids = |f: fn(&penumbra::AovPixel) -> u32| -> PyResult<Bound<'py, PyAny>> {
            let mut data = result_buffer(w * h, (w, h))?;
            data.extend(px.iter().map(f));
            Ok(Array2::from_shape_vec((h, w), data)
                .map_err(err)?
                .into_pyarray(py)
                .into_any())
        };
        let value = match name.as_str() {
            "depth" => {
                let mut data = result_buffer(w * h, (w, h))?;
                data.extend(px.iter().map(|p| p.depth));
                Array2::from_shape_vec((h, w), data)
                    .map_err(err)?
                    .into_pyarray(py)
                    .into_any()
            }
            "normal" => vec3(|p| p.normal)?,
            "albedo" => vec3(|p| p.albedo)?,
            "position" => vec3(|p| p.position)?,
            "object_id" => ids(|p| p.object_id)?,
            _ => ids(|p| p.primitive_id)?,
        };
        dict.set_item(name, value)?;
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
