//! Image files: writing films as PNG, JPEG, EXR or PFM (atomically: a temporary file in the
//! same folder, renamed into place), and decoding texture images to linear RGB.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use image::codecs::jpeg::JpegEncoder;
use image::{ImageBuffer, ImageEncoder, Rgb32FImage, RgbImage};
use thiserror::Error;

use crate::encode8::encode_all;
use crate::film::Film;
use crate::texture::{linear_to_srgb, srgb_to_linear, Image};

/// Output file formats, chosen by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// 8-bit sRGB (or gamma-encoded) PNG.
    Png,
    /// 8-bit sRGB (or gamma-encoded) JPEG.
    Jpeg,
    /// Linear float OpenEXR.
    Exr,
    /// Linear float Portable Float Map.
    Pfm,
}

impl OutputFormat {
    /// The largest width and height the format can store (JPEG: 65535), or `None` when only
    /// memory limits it.
    pub fn max_dimension(self) -> Option<u32> {
        match self {
            OutputFormat::Jpeg => Some(u16::MAX as u32),
            OutputFormat::Png | OutputFormat::Exr | OutputFormat::Pfm => None,
        }
    }

    /// The format named by `path`'s extension (case-insensitive).
    pub fn from_path(path: &Path) -> Option<OutputFormat> {
        Some(
            match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
                "png" => OutputFormat::Png,
                "jpg" | "jpeg" => OutputFormat::Jpeg,
                "exr" => OutputFormat::Exr,
                "pfm" => OutputFormat::Pfm,
                _ => return None,
            },
        )
    }
}

/// Why an image could not be written or read.
#[derive(Debug, Error)]
pub enum ImageError {
    /// The extension is not one of .png, .jpg, .jpeg, .exr, .pfm.
    #[error("{}: unknown image format (use .png, .jpg, .exr or .pfm)", path.display())]
    UnknownFormat {
        /// The path.
        path: PathBuf,
    },
    /// Writing failed.
    #[error("{}: cannot write image: {message}", path.display())]
    Write {
        /// The path.
        path: PathBuf,
        /// The cause.
        message: String,
    },
}

/// The 8-bit code of a linear value: `round(255·encode(clamp(c, 0, 1)))` with the sRGB curve,
/// or `c^(1/gamma)` when `gamma` is given.
pub fn encode_8bit(c: f32, gamma: Option<f32>) -> u8 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    let e = match gamma {
        Some(g) => c.powf(1.0 / g),
        None => linear_to_srgb(c),
    };
    (255.0 * e).round() as u8
}

/// Writes `film` to `path` in the format its extension names. The file appears complete or not
/// at all.
pub fn write_image(film: &Film, path: &Path, gamma: Option<f32>) -> Result<(), ImageError> {
    let format = OutputFormat::from_path(path).ok_or_else(|| ImageError::UnknownFormat {
        path: path.to_owned(),
    })?;
    let write_err = |message: String| ImageError::Write {
        path: path.to_owned(),
        message,
    };
    let name = path
        .file_name()
        .ok_or_else(|| write_err("not a file name".into()))?;
    // Unique per process and per call, so concurrent writers never share a temporary file.
    static WRITES: AtomicU64 = AtomicU64::new(0);
    let tmp = path.with_file_name(format!(
        ".{}.tmp-{}-{}",
        name.to_string_lossy(),
        std::process::id(),
        WRITES.fetch_add(1, Ordering::Relaxed)
    ));
    let result = write_to(film, &tmp, format, gamma)
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
    if let Err(message) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(write_err(message));
    }
    Ok(())
}

fn write_to(
    film: &Film,
    path: &Path,
    format: OutputFormat,
    gamma: Option<f32>,
) -> Result<(), String> {
    let file = File::create(path).map_err(|e| e.to_string())?;
    let mut w = BufWriter::new(file);
    let (width, height) = (film.width, film.height);
    let err = |e: image::ImageError| e.to_string();
    match format {
        OutputFormat::Png | OutputFormat::Jpeg => {
            let bytes = encode_all(&film.pixels, gamma);
            let img = RgbImage::from_raw(width, height, bytes).ok_or("bad film size")?;
            if format == OutputFormat::Png {
                img.write_to(&mut w, image::ImageFormat::Png).map_err(err)?;
            } else {
                JpegEncoder::new_with_quality(&mut w, 95)
                    .write_image(&img, width, height, image::ExtendedColorType::Rgb8)
                    .map_err(err)?;
            }
        }
        OutputFormat::Exr => {
            let floats: Vec<f32> = film.pixels.iter().flat_map(|p| p.to_array()).collect();
            let img: Rgb32FImage =
                ImageBuffer::from_raw(width, height, floats).ok_or("bad film size")?;
            img.write_to(&mut w, image::ImageFormat::OpenExr)
                .map_err(err)?;
        }
        OutputFormat::Pfm => {
            // Negative scale means little-endian; scanlines go bottom to top.
            write!(w, "PF\n{width} {height}\n-1.0\n").map_err(|e| e.to_string())?;
            for row in film.pixels.chunks(width as usize).rev() {
                for p in row {
                    for c in p.to_array() {
                        w.write_all(&c.to_le_bytes()).map_err(|e| e.to_string())?;
                    }
                }
            }
        }
    }
    let file = w.into_inner().map_err(|e| e.to_string())?;
    file.sync_all().map_err(|e| e.to_string())
}

/// Most texels in a texture: 2^26 (8192 × 8192), 768 MiB as linear float RGB.
pub const MAX_TEXELS: u64 = 1 << 26;

/// Decodes a PNG or JPEG (8 or 16 bits, grey, RGB or RGBA; alpha ignored) to linear RGB,
/// through the sRGB curve when `srgb` is true, else as value/max.
pub fn load_texture_image(path: &Path, srgb: bool) -> Result<Image, String> {
    // A compressed image over 1 GiB is not a texture; a folder, device or pipe is refused
    // before it is opened.
    crate::files::check_regular(path, 1 << 30).map_err(|e| e.to_string())?;
    let reader = || {
        image::ImageReader::open(path)
            .map_err(|e| e.to_string())?
            .with_guessed_format()
            .map_err(|e| e.to_string())
    };
    // Read the size from the header first: a small file can claim a huge image.
    let (w, h) = reader()?.into_dimensions().map_err(|e| e.to_string())?;
    if w as u64 * h as u64 > MAX_TEXELS {
        return Err(format!(
            "the image is too large for memory ({w}x{h}; at most {MAX_TEXELS} texels)"
        ));
    }
    let img = reader()?.decode().map_err(|e| e.to_string())?;
    let (width, height) = (img.width(), img.height());
    if width == 0 || height == 0 {
        return Err("the image is empty".into());
    }
    let rgb = img.into_rgb32f();
    let texels = rgb
        .pixels()
        .map(|p| {
            let c = glam::Vec3::from(p.0);
            if srgb {
                c.map(srgb_to_linear)
            } else {
                c
            }
        })
        .collect();
    Ok(Image {
        width,
        height,
        texels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eight_bit_encoding_follows_the_srgb_curve_and_clamps() {
        assert_eq!(encode_8bit(0.0, None), 0);
        assert_eq!(encode_8bit(1.0, None), 255);
        assert_eq!(encode_8bit(7.0, None), 255);
        assert_eq!(encode_8bit(-1.0, None), 0);
        // sRGB(0.18) = 0.4614 → 117.7 → 118.
        assert_eq!(encode_8bit(0.18, None), 118);
        // gamma 2.2: 0.5^(1/2.2) = 0.7297 → 186.
        assert_eq!(encode_8bit(0.5, Some(2.2)), 186);
        assert_eq!(encode_8bit(f32::NAN, None), 0);
    }

    #[test]
    fn textures_decode_8_and_16_bit_grey_rgb_and_rgba_to_linear() {
        let dir = std::env::temp_dir().join(format!("penumbra-decode-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // Each image holds one texel whose encoded value is one half (128/255 or 32768/65535).
        let half8 = 128.0 / 255.0;
        let half16 = 32768.0 / 65535.0;
        let cases: Vec<(&str, image::DynamicImage, f32)> = vec![
            (
                "grey8.png",
                image::GrayImage::from_pixel(1, 1, image::Luma([128])).into(),
                half8,
            ),
            (
                "grey16.png",
                image::ImageBuffer::<image::Luma<u16>, _>::from_pixel(1, 1, image::Luma([32768]))
                    .into(),
                half16,
            ),
            (
                "rgb8.png",
                image::RgbImage::from_pixel(1, 1, image::Rgb([128; 3])).into(),
                half8,
            ),
            (
                "rgba16.png",
                image::ImageBuffer::<image::Rgba<u16>, _>::from_pixel(
                    1,
                    1,
                    image::Rgba([32768, 32768, 32768, 0]),
                )
                .into(),
                half16,
            ),
            // Alpha is ignored: a fully transparent texel keeps its color.
            (
                "rgba8.png",
                image::RgbaImage::from_pixel(1, 1, image::Rgba([128, 128, 128, 0])).into(),
                half8,
            ),
        ];
        for (name, img, encoded) in cases {
            let path = dir.join(name);
            img.save(&path).unwrap();
            let srgb = load_texture_image(&path, true).unwrap();
            let linear = load_texture_image(&path, false).unwrap();
            assert_eq!((srgb.width, srgb.height), (1, 1));
            for c in srgb.texels[0].to_array() {
                assert!((c - srgb_to_linear(encoded)).abs() < 1e-6, "{name}: {c}");
            }
            for c in linear.texels[0].to_array() {
                assert!((c - encoded).abs() < 1e-6, "{name}: {c}");
            }
        }
        let corrupt = dir.join("corrupt.png");
        std::fs::write(&corrupt, b"not a png").unwrap();
        assert!(load_texture_image(&corrupt, true).is_err());
        assert!(load_texture_image(&dir.join("missing.png"), true).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn output_formats_by_extension() {
        assert_eq!(
            OutputFormat::from_path(Path::new("a.PNG")),
            Some(OutputFormat::Png)
        );
        assert_eq!(
            OutputFormat::from_path(Path::new("a.jpeg")),
            Some(OutputFormat::Jpeg)
        );
        assert_eq!(
            OutputFormat::from_path(Path::new("a.exr")),
            Some(OutputFormat::Exr)
        );
        assert_eq!(
            OutputFormat::from_path(Path::new("a.pfm")),
            Some(OutputFormat::Pfm)
        );
        assert_eq!(OutputFormat::from_path(Path::new("a.bmp")), None);
        assert_eq!(OutputFormat::from_path(Path::new("a")), None);
    }
}
