//! Image files: writing films as PNG, JPEG, EXR or PFM (atomically: a temporary file in the
//! same folder, renamed into place), and decoding texture images to linear RGB.

use std::fs::File;
use std::io::{BufWriter, Cursor, Seek, SeekFrom, Write};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

mod encode;

use crate::film::Film;
use crate::image_error::ImageError;
use crate::image_format::OutputFormat;
use crate::math::Rgb;
use crate::staged::StagedFile;
use encode::{encode, prepare};

/// Writes `film` to `path` in the format its extension names. The file appears complete or not
/// at all.
pub fn write_image(film: &Film, path: &Path, gamma: Option<f32>) -> Result<(), ImageError> {
    write_image_unless(film, path, gamma, &AtomicBool::new(false))
}

/// [`write_image`], stopped by `cancel`: checked before every write to the temporary file and
/// before it is renamed into place. Once set, the temporary file is removed and the call
/// returns [`ImageError::Cancelled`], leaving `path` as it was (absent, or the old file).
pub fn write_image_unless(
    film: &Film,
    path: &Path,
    gamma: Option<f32>,
    cancel: &AtomicBool,
) -> Result<(), ImageError> {
    let staged = stage_image(film, path, gamma, cancel)?;
    if cancel.load(Ordering::SeqCst) {
        return Err(ImageError::Cancelled);
    }
    staged.commit()
}

/// An error naming the first pixel of `film` that is infinite or NaN, for a float format
/// (EXR, PFM: SPEC §7 writes floats unclamped, so such a value would be a lie); `Ok` for the
/// 8-bit formats, which clamp.
pub fn check_finite(film: &Film, path: &Path, format: OutputFormat) -> Result<(), ImageError> {
    if !matches!(format, OutputFormat::Exr | OutputFormat::Pfm) {
        return Ok(());
    }
    // A branch-free pass first (vectorized, where a search that stops at the first bad value
    // runs one value at a time), then the search only when something is bad (measured:
    // docs/benchmarks.md, «Design measurements», `check_finite`).
    let finite = |p: &Rgb| p.x.is_finite() & p.y.is_finite() & p.z.is_finite();
    if film.pixels.iter().fold(true, |all, p| all & finite(p)) {
        return Ok(());
    }
    let bad = film.pixels.iter().enumerate().find_map(|(i, p)| {
        let value = p.to_array().into_iter().find(|c| !c.is_finite())?;
        Some((i, value))
    });
    match bad {
        None => Ok(()),
        Some((i, value)) => {
            let width = film.width.max(1) as usize;
            Err(ImageError::NonFinite {
                path: path.to_owned(),
                x: (i % width) as u32,
                y: (i / width) as u32,
                value,
            })
        }
    }
}

/// Refuses to encode `film` as `format` (for `path`; its bytes kept `in_memory` or not) when
/// `gamma` is not one, the format cannot store the film's size, or the encoding would need
/// more than the `available` memory: before anything is converted or written.
fn check_encodable(
    film: &Film,
    format: OutputFormat,
    gamma: Option<f32>,
    path: &Path,
    in_memory: bool,
    available: Option<u64>,
) -> Result<(), ImageError> {
    ImageError::check_gamma(gamma)?;
    if film.alpha.is_some() && !format.has_alpha() {
        return Err(ImageError::NoAlpha {
            path: path.to_owned(),
            format: format.name(),
        });
    }
    let (width, height) = (film.width, film.height);
    if let Some(limit) = format.max_dimension().filter(|&l| width.max(height) > l) {
        return Err(ImageError::TooLarge {
            path: path.to_owned(),
            width,
            height,
            format: format.name(),
            limit,
        });
    }
    let need = film.pixels.len() as u64 * format.bytes_per_pixel(in_memory);
    match available {
        Some(available) if need > available => Err(ImageError::OutOfMemory {
            path: path.to_owned(),
            width,
            height,
            format: format.name(),
            need,
            available,
        }),
        _ => Ok(()),
    }
}

/// [`write_image_unless`] without the final rename: the image written beside `path` under a
/// temporary name, to be renamed into place with other files (an image and its AOVs) by
/// [`commit_all`](crate::commit_all), or removed when dropped.
pub fn stage_image(
    film: &Film,
    path: &Path,
    gamma: Option<f32>,
    cancel: &AtomicBool,
) -> Result<StagedFile, ImageError> {
    let format = OutputFormat::from_path(path).ok_or_else(|| ImageError::UnknownFormat {
        path: path.to_owned(),
    })?;
    check_encodable(film, format, gamma, path, false, crate::memory::available())?;
    check_finite(film, path, format)?;
    StagedFile::write_with(path, |file| write_to(film, file, format, gamma, cancel)).map_err(|e| {
        if cancel.load(Ordering::SeqCst) {
            ImageError::Cancelled
        } else {
            e
        }
    })
}

/// The bytes an image file is written in at a time.
const WRITE_BUFFER: usize = 1 << 20;

/// A file whose writes fail once `cancel` is set, so that an encoder stops at its next write.
struct Unless<'a> {
    file: &'a mut File,
    cancel: &'a AtomicBool,
}

impl Write for Unless<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.cancel.load(Ordering::Relaxed) {
            // Not ErrorKind::Interrupted, which write_all would retry.
            return Err(std::io::Error::other("interrupted"));
        }
        self.file.write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

impl Seek for Unless<'_> {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.file.seek(pos)
    }
}

/// `film` encoded in `format`, as the bytes [`write_image`] would write (for a pipe, say:
/// errors name the path "standard output").
pub fn encode_image(
    film: &Film,
    format: OutputFormat,
    gamma: Option<f32>,
) -> Result<Vec<u8>, ImageError> {
    let path = Path::new("standard output");
    check_encodable(film, format, gamma, path, true, crate::memory::available())?;
    let encode_err = |message: String| ImageError::Encode { message };
    let never = AtomicBool::new(false);
    let prepared = prepare(film, format, gamma, &never)
        .map_err(encode_err)?
        .ok_or_else(|| encode_err("interrupted".into()))?;
    let mut w = Cursor::new(Vec::new());
    encode(film, &prepared, format, &mut w).map_err(encode_err)?;
    Ok(w.into_inner())
}

fn write_to(
    film: &Film,
    file: &mut File,
    format: OutputFormat,
    gamma: Option<f32>,
    cancel: &AtomicBool,
) -> Result<(), String> {
    let interrupted = || "interrupted".to_owned();
    let prepared = prepare(film, format, gamma, cancel)?.ok_or_else(interrupted)?;
    // Large writes: at 8 KiB a 1024² float image took 1,500 system calls.
    let mut w = BufWriter::with_capacity(WRITE_BUFFER, Unless { file, cancel });
    encode(film, &prepared, format, &mut w)?;
    w.flush().map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests;
