//! The library's errors as Python exceptions: scene mistakes as `SceneError` (a `ValueError`)
//! with their location, unreadable files as `OSError` subclasses, bad settings as
//! `ValueError`, an interrupted render as `KeyboardInterrupt`.

use penumbra::products::ProductError;
use penumbra::{AssetKind, ErrorKind, ImageError, RaycastError, RenderError};
use pyo3::exceptions::{PyKeyboardInterrupt, PyMemoryError, PyOSError, PyValueError};
use pyo3::prelude::*;

pyo3::create_exception!(
    penumbra,
    SceneError,
    PyValueError,
    "A mistake in a scene: its attributes `file`, `line`, `column` (1-based, or None), `key` \
     (the key path such as `objects[2].material`, or None) and `kind` say where and what."
);

/// The name of an error kind, as the Python API spells it.
fn kind_name(kind: ErrorKind) -> &'static str {
    match kind {
        ErrorKind::Syntax => "syntax",
        ErrorKind::UnknownKey => "unknown_key",
        ErrorKind::MissingKey => "missing_key",
        ErrorKind::BadValue => "bad_value",
        ErrorKind::UnknownName => "unknown_name",
        ErrorKind::Asset(AssetKind::Mesh) => "asset_mesh",
        ErrorKind::Asset(AssetKind::Image) => "asset_image",
        ErrorKind::Asset(AssetKind::Transforms) => "asset_transforms",
        ErrorKind::File => "file",
    }
}

/// An `OSError` of the right subclass (`FileNotFoundError`, `PermissionError`, ...) for `e`,
/// naming `path`, as `open()` raises it.
pub(crate) fn os_error(e: &std::io::Error, path: &std::path::Path) -> PyErr {
    let path = path.display().to_string();
    match e.raw_os_error() {
        Some(errno) => PyOSError::new_err((errno, e.to_string(), path)),
        None => PyOSError::new_err(format!("{path}: {e}")),
    }
}

/// A scene error as Python sees it. A scene file that cannot be read is an `OSError`, with the
/// operating system's error number and the file name; everything else is a [`SceneError`].
pub(crate) fn scene_error(py: Python<'_>, e: penumbra::SceneError) -> PyErr {
    if let penumbra::SceneError::Read { path, source } = &e {
        return os_error(source, path);
    }
    let err = SceneError::new_err(e.to_string());
    let value = err.value(py);
    let location = e.location();
    let file = match (&e, location) {
        (_, Some(l)) => Some(l.file.display().to_string()),
        (penumbra::SceneError::UnknownFormat { path }, None) => Some(path.display().to_string()),
        _ => None,
    };
    // Setting attributes on a fresh exception object cannot fail but for memory exhaustion;
    // the message stays right either way.
    let _ = value.setattr("file", file);
    let _ = value.setattr("line", location.and_then(|l| l.line));
    let _ = value.setattr("column", location.and_then(|l| l.column));
    let _ = value.setattr("key", location.and_then(|l| l.key.clone()));
    let _ = value.setattr("kind", kind_name(e.kind()));
    err
}

/// A render error as Python sees it.
pub(crate) fn render_error(e: RenderError) -> PyErr {
    match e {
        RenderError::Cancelled => PyKeyboardInterrupt::new_err("render interrupted"),
        RenderError::OutOfMemory { .. } => PyMemoryError::new_err(format!("Scene.render: {e}")),
        RenderError::Settings(_) | RenderError::BadRegion { .. } => {
            PyValueError::new_err(e.to_string())
        }
        RenderError::Threads { threads, .. } if threads > penumbra::MAX_THREADS => {
            PyValueError::new_err(e.to_string())
        }
        RenderError::Threads { .. } => PyOSError::new_err(e.to_string()),
    }
}

/// An image error as Python sees it: an unknown extension, a bad gamma or an image that cannot
/// be encoded (too large for its format, alpha for a format without it, non-finite values in
/// a float format) is a
/// `ValueError`, one beyond the memory available a `MemoryError`, a failed write an `OSError`,
/// a cancelled one `KeyboardInterrupt`; its message names `call`.
pub(crate) fn image_error(call: &str, e: ImageError) -> PyErr {
    let message = format!("{call}: {e}");
    match e {
        ImageError::UnknownFormat { .. }
        | ImageError::Encode { .. }
        | ImageError::BadGamma(_)
        | ImageError::TooLarge { .. }
        | ImageError::NoAlpha { .. }
        | ImageError::NonFinite { .. } => PyValueError::new_err(message),
        ImageError::OutOfMemory { .. } => PyMemoryError::new_err(message),
        ImageError::Write { .. } => PyOSError::new_err(message),
        ImageError::Cancelled => PyKeyboardInterrupt::new_err(message),
    }
}

/// A file that could not be written, as Python sees it: when the system said why (an error
/// number), the `OSError` subclass `open()` raises for it (`PermissionError`,
/// `FileNotFoundError`, ...) naming the file asked for, never the temporary file it was
/// staged under; any other image error as [`image_error`] has it.
pub(crate) fn write_error(call: &str, e: ImageError) -> PyErr {
    if let ImageError::Write { path, message } = &e {
        // The system's reason ends the message as io::Error writes it: "... (os error 13)".
        let numbered = message
            .strip_suffix(')')
            .and_then(|m| m.rsplit_once(" (os error "))
            .and_then(|(reason, n)| Some((reason, n.parse::<i32>().ok()?)));
        if let Some((reason, errno)) = numbered {
            let path = path.display().to_string();
            return PyOSError::new_err((errno, format!("{call}: cannot write: {reason}"), path));
        }
    }
    image_error(call, e)
}

/// A batch's file that could not be made or written (see [`write_error`]): values the
/// format cannot hold are a `ValueError`, no memory a `MemoryError`, the rest `OSError`.
pub(crate) fn product_error(call: &str, e: ProductError) -> PyErr {
    match e {
        ProductError::Image(e) => write_error(call, e),
        ProductError::Memory(_) => PyMemoryError::new_err(format!("{call}: {e}")),
        ProductError::Invalid { .. } => PyValueError::new_err(format!("{call}: {e}")),
        ProductError::Io { .. } => PyOSError::new_err(format!("{call}: {e}")),
    }
}

/// A buffer for `len` values, or a `MemoryError` saying that `call` has no memory for
/// `what`.
pub(crate) fn buffer<T>(call: &str, what: &str, len: usize) -> PyResult<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| no_memory(call, what))?;
    Ok(v)
}

/// The `MemoryError` saying that `call` has no memory for `what`.
pub(crate) fn no_memory(call: &str, what: &str) -> PyErr {
    PyMemoryError::new_err(format!("{call}: not enough memory for {what}"))
}

/// A ray-casting error as Python sees it: bad meshes, cameras or arguments are a `ValueError`,
/// a cancelled query `KeyboardInterrupt`, worker threads that cannot start an `OSError`.
pub(crate) fn raycast_error(e: RaycastError) -> PyErr {
    match e {
        RaycastError::Cancelled => PyKeyboardInterrupt::new_err("ray casting interrupted"),
        RaycastError::Threads(_) => PyOSError::new_err(e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    }
}
