//! Image files: writing films as PNG, JPEG, EXR or PFM (atomically: a temporary file in the
//! same folder, renamed into place), and decoding texture images to linear RGB.

use std::fs::File;
use std::io::{BufWriter, Cursor, Seek, SeekFrom, Write};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};

use image::codecs::jpeg::JpegEncoder;
use image::{ImageBuffer, ImageEncoder, Rgb32FImage, RgbImage};

use crate::encode8::encode_all;
use crate::film::Film;
use crate::image_error::ImageError;
use crate::image_format::OutputFormat;
use crate::math::Rgb;
use crate::staged::StagedFile;

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

/// A film converted for its format, ready to be encoded.
enum Prepared {
    /// 8-bit codes, for PNG and JPEG.
    Rgb8(RgbImage),
    /// Linear floats, for EXR.
    Rgb32F(Rgb32FImage),
    /// Nothing to convert: PFM writes the film's floats as they are.
    Floats,
}

/// Converts `film` for `format`, row by row; `None` once `cancel` is set.
fn prepare(
    film: &Film,
    format: OutputFormat,
    gamma: Option<f32>,
    cancel: &AtomicBool,
) -> Result<Option<Prepared>, String> {
    let (width, height) = (film.width, film.height);
    let rows = film.pixels.chunks(width.max(1) as usize);
    let cancelled = || cancel.load(Ordering::Relaxed);
    Ok(Some(match format {
        OutputFormat::Png | OutputFormat::Jpeg => {
            // A table lookup per channel: quick enough not to need checking in between.
            if cancelled() {
                return Ok(None);
            }
            let bytes = encode_all(&film.pixels, gamma);
            Prepared::Rgb8(RgbImage::from_raw(width, height, bytes).ok_or("bad film size")?)
        }
        OutputFormat::Exr => {
            let mut floats = Vec::new();
            floats
                .try_reserve_exact(film.pixels.len() * 3)
                .map_err(|_| format!("not enough memory for a {width}x{height} image"))?;
            for row in rows {
                if cancelled() {
                    return Ok(None);
                }
                floats.extend(row.iter().flat_map(|p| p.to_array()));
            }
            Prepared::Rgb32F(ImageBuffer::from_raw(width, height, floats).ok_or("bad film size")?)
        }
        OutputFormat::Pfm => Prepared::Floats,
    }))
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

/// Writes the prepared film to `w` in `format`.
fn encode<W: Write + Seek>(
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
        Prepared::Rgb32F(img) => {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cancelled_write_leaves_the_old_file_and_no_temporary_file() {
        let dir = std::env::temp_dir().join(format!("penumbra-cancel-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let film = Film {
            width: 2,
            height: 1,
            pixels: vec![glam::Vec3::ONE; 2],
        };
        for ext in ["png", "jpg", "exr", "pfm"] {
            let path = dir.join(format!("out.{ext}"));
            std::fs::write(&path, b"old").unwrap();
            let got = write_image_unless(&film, &path, None, &AtomicBool::new(true));
            assert!(matches!(got, Err(ImageError::Cancelled)), "{ext}: {got:?}");
            assert_eq!(std::fs::read(&path).unwrap(), b"old", "{ext}");
            write_image_unless(&film, &path, None, &AtomicBool::new(false)).unwrap();
            assert_ne!(std::fs::read(&path).unwrap(), b"old", "{ext}");
        }
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 4, "temporary files left: {names:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn pfm_rows_go_bottom_up_across_several_writes() {
        // 3,600 bytes a row: 292 rows a write, so 700 rows take three writes, the last short.
        let (width, height) = (300u32, 700u32);
        let pixels: Vec<glam::Vec3> = (0..width * height)
            .map(|i| glam::Vec3::new(i as f32, -(i as f32), 0.5 + i as f32))
            .collect();
        let film = Film {
            width,
            height,
            pixels,
        };
        let mut w = BufWriter::with_capacity(WRITE_BUFFER, Cursor::new(Vec::new()));
        encode(&film, &Prepared::Floats, OutputFormat::Pfm, &mut w).unwrap();
        let bytes = w.into_inner().unwrap().into_inner();
        let header = format!("PF\n{width} {height}\n-1.0\n");
        assert_eq!(&bytes[..header.len()], header.as_bytes());
        let floats: Vec<f32> = bytes[header.len()..]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        let want: Vec<f32> = film
            .pixels
            .chunks(width as usize)
            .rev()
            .flatten()
            .flat_map(|p| p.to_array())
            .collect();
        assert!(
            floats == want,
            "the file's floats are not the film's rows bottom up"
        );
    }

    #[test]
    fn float_formats_never_store_a_non_finite_value() {
        let dir = std::env::temp_dir().join(format!("penumbra-nonfinite-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for bad in [f32::INFINITY, f32::NEG_INFINITY, f32::NAN] {
            let film = Film {
                width: 3,
                height: 2,
                pixels: (0..6)
                    .map(|i| glam::Vec3::splat(if i == 4 { bad } else { 0.5 }))
                    .collect(),
            };
            for ext in ["exr", "pfm"] {
                let path = dir.join(format!("out.{ext}"));
                let got = write_image(&film, &path, None);
                let Err(ImageError::NonFinite { x: 1, y: 1, .. }) = got else {
                    panic!("{ext} {bad}: {got:?}");
                };
                assert!(!path.exists(), "{ext} {bad}: a file was written");
            }
            // 8-bit formats clamp (NaN to 0), as SPEC §7 says.
            write_image(&film, &dir.join("out.png"), None).unwrap();
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// What cannot be encoded is refused before anything is converted or written: a gamma
    /// that is not one, a JPEG wider or higher than 65535 pixels, an encoding beyond the
    /// memory available.
    #[test]
    fn unencodable_images_are_refused_up_front() {
        let dir = std::env::temp_dir().join(format!("penumbra-refused-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let film = |width: u32, height: u32| Film {
            width,
            height,
            pixels: vec![glam::Vec3::splat(0.5); (width * height) as usize],
        };
        let small = film(2, 2);
        let bad_gammas = [
            0.0,
            -0.0,
            -2.2,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            1e-40,
        ];
        for g in bad_gammas {
            for name in ["g.png", "g.jpg"] {
                let got = write_image(&small, &dir.join(name), Some(g));
                assert!(matches!(got, Err(ImageError::BadGamma(_))), "{g}: {got:?}");
                assert!(!dir.join(name).exists(), "{g}: {name} written");
            }
            let got = encode_image(&small, OutputFormat::Png, Some(g));
            assert!(matches!(got, Err(ImageError::BadGamma(_))), "{g}: {got:?}");
        }
        for (width, height) in [(65_536, 1), (1, 65_536)] {
            let wide = film(width, height);
            let got = write_image(&wide, &dir.join("w.jpg"), None).unwrap_err();
            assert!(matches!(got, ImageError::TooLarge { .. }), "{got:?}");
            assert!(got.to_string().contains("65535"), "{got}");
            assert!(!dir.join("w.jpg").exists());
            let got = encode_image(&wide, OutputFormat::Jpeg, None).unwrap_err();
            assert!(matches!(got, ImageError::TooLarge { .. }), "{got:?}");
        }
        write_image(&film(65_535, 1), &dir.join("w.jpg"), Some(2.2)).unwrap();
        // 1000 × 1000 pixels as a PNG need about 7 MB beyond the film.
        let big = film(1000, 1000);
        let path = Path::new("big.png");
        let cases = [
            (OutputFormat::Png, false, Some(1 << 20), false),
            (OutputFormat::Png, false, Some(100 << 20), true),
            (OutputFormat::Png, false, None, true),
            (OutputFormat::Exr, false, Some(10 << 20), false),
            (OutputFormat::Pfm, false, Some(0), true),
            (OutputFormat::Pfm, true, Some(10 << 20), false),
        ];
        for (format, in_memory, available, fits) in cases {
            let got = check_encodable(&big, format, None, path, in_memory, available);
            assert_eq!(
                got.is_ok(),
                fits,
                "{format:?} {in_memory} {available:?}: {got:?}"
            );
            if let Err(e) = got {
                let text = e.to_string();
                assert!(
                    text.contains("1000x1000") && text.contains("memory"),
                    "{text}"
                );
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn encoded_bytes_are_the_bytes_written() {
        let film = Film {
            width: 3,
            height: 2,
            pixels: (0..6)
                .map(|i| crate::math::Rgb::new(i as f32 / 5.0, 0.5, 2.0))
                .collect(),
        };
        let dir = std::env::temp_dir().join(format!("penumbra-encode-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for (name, format) in [
            ("a.png", OutputFormat::Png),
            ("a.pfm", OutputFormat::Pfm),
            ("a.exr", OutputFormat::Exr),
            ("a.jpg", OutputFormat::Jpeg),
        ] {
            let path = dir.join(name);
            write_image(&film, &path, None).unwrap();
            let written = std::fs::read(&path).unwrap();
            assert_eq!(
                encode_image(&film, format, None).unwrap(),
                written,
                "{name}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
