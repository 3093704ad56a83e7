//! How a film becomes the bytes of its format: 8-bit codes for PNG and JPEG (PNG with
//! straight alpha), linear floats for EXR (premultiplied alpha, OpenEXR's convention), and
//! PFM's rows of floats, bottom row first.

use std::io::{Seek, Write};
use std::sync::atomic::{AtomicBool, Ordering};

use image::codecs::jpeg::JpegEncoder;
use image::{ImageBuffer, ImageEncoder, Rgb32FImage, RgbImage, Rgba32FImage, RgbaImage};

use super::WRITE_BUFFER;
use crate::encode8::film_codes;
use crate::film::Film;
use crate::image_format::OutputFormat;

/// A film converted for its format, ready to be encoded.
pub(super) enum Prepared {
    /// 8-bit codes, for PNG and JPEG.
    Rgb8(RgbImage),
    /// 8-bit codes of the unpremultiplied colour and linear alpha, for PNG.
    Rgba8(RgbaImage),
    /// Linear floats, for EXR.
    Rgb32F(Rgb32FImage),
    /// Linear floats, premultiplied, and alpha, for EXR.
    Rgba32F(Rgba32FImage),
    /// Nothing to convert: PFM writes the film's floats as they are.
    Floats,
}

/// Converts `film` for `format`, row by row; `None` once `cancel` is set.
pub(super) fn prepare(
    film: &Film,
    format: OutputFormat,
    gamma: Option<f32>,
    cancel: &AtomicBool,
) -> Result<Option<Prepared>, String> {
    let (width, height) = (film.width, film.height);
    let rows = film.pixels.chunks(width.max(1) as usize);
    let cancelled = || cancel.load(Ordering::Relaxed);
    let too_large = || format!("not enough memory for a {width}x{height} image");
    let bad_size = "bad film size";
    Ok(Some(match (format, &film.alpha) {
        // JPEG with alpha is refused by `check_encodable`.
        (OutputFormat::Png | OutputFormat::Jpeg, alpha) => {
            // A table lookup per channel: quick enough not to need checking in between.
            if cancelled() {
                return Ok(None);
            }
            let bytes = film_codes(film, gamma);
            match alpha {
                Some(_) => {
                    Prepared::Rgba8(RgbaImage::from_raw(width, height, bytes).ok_or(bad_size)?)
                }
                None => Prepared::Rgb8(RgbImage::from_raw(width, height, bytes).ok_or(bad_size)?),
            }
        }
        (OutputFormat::Exr, alpha) => {
            let channels = if alpha.is_some() { 4 } else { 3 };
            let mut floats = Vec::new();
            floats
                .try_reserve_exact(film.pixels.len() * channels)
                .map_err(|_| too_large())?;
            for (y, row) in rows.enumerate() {
                if cancelled() {
                    return Ok(None);
                }
                match alpha {
                    Some(alpha) => {
                        let alpha = &alpha[y * width as usize..];
                        let rgba = row.iter().zip(alpha).map(|(p, &a)| p.extend(a).to_array());
                        floats.extend(rgba.flatten());
                    }
                    None => floats.extend(row.iter().flat_map(|p| p.to_array())),
                }
            }
            match alpha {
                Some(_) => {
                    Prepared::Rgba32F(ImageBuffer::from_raw(width, height, floats).ok_or(bad_size)?)
                }
                None => {
                    Prepared::Rgb32F(ImageBuffer::from_raw(width, height, floats).ok_or(bad_size)?)
                }
            }
        }
        // Refused with alpha by `check_encodable`.
        (OutputFormat::Pfm, _) => Prepared::Floats,
    }))
}

/// Writes the prepared film to `w` in `format`.
pub(super) fn encode<W: Write + Seek>(
    film: &Film,
    prepared: &Prepared,
    format: OutputFormat,
    mut w: W,
) -> Result<(), String> {
    let (width, height) = (film.width, film.height);
    let err = |e: image::ImageError| e.to_string();
    match prepared {
        Prepared::Rgb8(img) => {
            if format == OutputFormat::Png {
                img.write_to(&mut w, image::ImageFormat::Png).map_err(err)?;
            } else {
                JpegEncoder::new_with_quality(&mut w, 95)
                    .write_image(img, width, height, image::ExtendedColorType::Rgb8)
                    .map_err(err)?;
            }
        }
        Prepared::Rgba8(img) => img.write_to(&mut w, image::ImageFormat::Png).map_err(err)?,
        Prepared::Rgb32F(img) => {
            img.write_to(&mut w, image::ImageFormat::OpenExr)
                .map_err(err)?;
        }
        Prepared::Rgba32F(img) => {
            img.write_to(&mut w, image::ImageFormat::OpenExr)
                .map_err(err)?;
        }
        Prepared::Floats => {
            // Negative scale means little-endian; scanlines go bottom to top.
            write!(w, "PF\n{width} {height}\n-1.0\n").map_err(|e| e.to_string())?;
            // Whole rows at a time, at least the writer's buffer so that they go straight to
            // the file (four bytes a call cost 3 million calls at 1024², and rows copied
            // through the buffer a second pass over 12 MB). Each pixel's twelve bytes go to
            // their place rather than being appended four at a time (measured:
            // docs/benchmarks.md, «Design measurements», PFM rows).
            let row_bytes = width as usize * 12;
            let rows = WRITE_BUFFER.div_ceil(row_bytes.max(1));
            let mut chunk = Vec::with_capacity(rows * row_bytes);
            let mut bottom_up = film.pixels.chunks(width as usize).rev().peekable();
            while bottom_up.peek().is_some() {
                chunk.clear();
                for row in bottom_up.by_ref().take(rows) {
                    let at = chunk.len();
                    chunk.resize(at + row_bytes, 0);
                    for (bytes, p) in chunk[at..].chunks_exact_mut(12).zip(row) {
                        for (to, c) in bytes.chunks_exact_mut(4).zip(p.to_array()) {
                            to.copy_from_slice(&c.to_le_bytes());
                        }
                    }
                }
                w.write_all(&chunk).map_err(|e| e.to_string())?;
            }
        }
    }
    w.flush().map_err(|e| e.to_string())
}
