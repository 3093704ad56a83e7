//! Texture images: PNG and JPEG files (and Radiance HDR and OpenEXR, for environment maps)
//! decoded to linear RGB texels (and the alpha channel, linear as stored, when the file has
//! one), with their size checked against memory before decoding (a small file can claim a
//! huge image). The format is the content's (its first bytes), never the file's extension,
//! and so is the colour curve: 8- and 16-bit PNG and JPEG are sRGB-encoded, Radiance HDR and
//! OpenEXR hold linear values (as Mitsuba's `Bitmap` reads them: format detected from the
//! content, the sRGB curve only for integer formats).

mod flat_hdr;

use std::io::Cursor;
use std::path::Path;

use image::{DynamicImage, ImageFormat};

use crate::files::Files;
use crate::texture::{srgb_to_linear, Image};

/// Most texels in a texture: 2^26 (8192 × 8192), 768 MiB as linear float RGB.
pub const MAX_TEXELS: u64 = 1 << 26;

/// Most bytes a decoder may allocate: [`MAX_TEXELS`] of its largest texel (four 32-bit
/// floats), the `image` crate's limit (its default, 512 MiB, refused a 10240 × 5120 HDR).
const MAX_DECODER_BYTES: u64 = MAX_TEXELS * 16;

/// Memory decoding takes per texel at its peak: the decoder's buffer (up to 8 bytes for
/// 16-bit RGBA), its float copy (12, or 16 with alpha), and the texels kept (12, and 4 for
/// the alpha).
pub const DECODE_BYTES_PER_TEXEL: u64 = 40;

/// Reads and decodes the PNG or JPEG `path` of `files` (8 or 16 bits, grey, RGB or RGBA)
/// to linear RGB, through the sRGB curve when `srgb` is true, else as value/max; an alpha
/// channel is kept beside the texels as value/max, never through the curve ([`Image::alpha`]).
/// A Radiance HDR or OpenEXR file is linear already: its values are kept, whatever `srgb`.
/// With `max_bytes`, an image whose decoding would take more memory than that is refused
/// before it is decoded.
pub(crate) fn load_texture_image(
    files: &Files,
    path: &Path,
    srgb: bool,
    max_bytes: Option<u64>,
) -> Result<Image, String> {
    // A compressed image over 1 GiB is not a texture; a folder, device or pipe is refused
    // before it is opened.
    let bytes = files.read(path, 1 << 30).map_err(|e| e.to_string())?;
    decode_texture_image(&bytes, srgb, max_bytes)
}

/// The eight bytes every PNG file starts with.
const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];

/// Refuses a PNG whose palette (a `PLTE` chunk) is not a whole number of RGB entries, or has
/// more than 256: png 0.18.1 accepts such a chunk and then panics while it expands the
/// paletted image (`decoder/transform/palette.rs`; found by fuzzing the `texture` target). Other
/// files, and PNGs with sound palettes, pass untouched.
fn check_png_palette(bytes: &[u8]) -> Result<(), String> {
    let Some(mut rest) = bytes.strip_prefix(&PNG_SIGNATURE[..]) else {
        return Ok(());
    };
    // Chunks: a 4-byte big-endian length, a 4-byte type, the data, a 4-byte CRC.
    while let [a, b, c, d, kind @ ..] = rest {
        let len = u32::from_be_bytes([*a, *b, *c, *d]) as usize;
        if kind.starts_with(b"PLTE") && (!len.is_multiple_of(3) || len > 3 * 256) {
            return Err(format!(
                "the PNG palette (PLTE chunk) has {len} bytes, not a whole number of RGB \
                 entries up to 256"
            ));
        }
        rest = rest.get(len.saturating_add(12)..).unwrap_or_default();
    }
    Ok(())
}

/// [`load_texture_image`] on the bytes of the image file.
pub fn decode_texture_image(
    bytes: &[u8],
    srgb: bool,
    max_bytes: Option<u64>,
) -> Result<Image, String> {
    check_png_palette(bytes)?;
    let reader = || {
        let mut reader = image::ImageReader::new(Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())?;
        let mut limits = image::Limits::default();
        limits.max_alloc = Some(MAX_DECODER_BYTES);
        reader.limits(limits);
        Ok::<_, String>(reader)
    };
    let format = reader()?.format();
    // Float content is linear: the curve is for integer (encoded) content only.
    let srgb = srgb && !matches!(format, Some(ImageFormat::Hdr | ImageFormat::OpenExr));
    // Read the size from the header first: a small file can claim a huge image.
    let (w, h) = reader()?.into_dimensions().map_err(|e| e.to_string())?;
    if w as u64 * h as u64 > MAX_TEXELS {
        return Err(format!(
            "the image is too large for memory ({w}x{h}; at most {MAX_TEXELS} texels)"
        ));
    }
    let need = w as u64 * h as u64 * DECODE_BYTES_PER_TEXEL;
    if let Some(max) = max_bytes.filter(|&max| need > max) {
        return Err(format!(
            "decoding this {w}x{h} image needs about {} of memory, more than the {} available",
            crate::memory::human(need),
            crate::memory::human(max)
        ));
    }
    let flat = match format {
        Some(ImageFormat::Hdr) => flat_hdr::decode(bytes),
        _ => None,
    };
    let img = match flat {
        Some(flat) => DynamicImage::from(flat?),
        None => reader()?.decode().map_err(|e| decode_error(&e))?,
    };
    let (width, height) = (img.width(), img.height());
    if width == 0 || height == 0 {
        return Err("the image is empty".into());
    }
    let texels = width as usize * height as usize;
    let room = || format!("not enough memory for a {width}x{height} image");
    let decode = |c: [f32; 3]| {
        let c = glam::Vec3::from(c);
        if srgb {
            c.map(srgb_to_linear)
        } else {
            c
        }
    };
    let (rgb, alpha) = if img.color().has_alpha() {
        let (mut rgb, mut alpha) = (
            room_for(texels).ok_or_else(room)?,
            room_for(texels).ok_or_else(room)?,
        );
        for p in img.into_rgba32f().pixels() {
            let [r, g, b, a] = p.0;
            rgb.push(decode([r, g, b]));
            alpha.push(a);
        }
        (rgb, Some(alpha))
    } else {
        let mut rgb = room_for(texels).ok_or_else(room)?;
        rgb.extend(img.into_rgb32f().pixels().map(|p| decode(p.0)));
        (rgb, None)
    };
    Ok(Image {
        width,
        height,
        texels: rgb,
        alpha,
    })
}

/// The message of a decoder's error; its memory limit named with the texel limit it follows.
fn decode_error(e: &image::ImageError) -> String {
    match e {
        image::ImageError::Limits(_) => format!(
            "{e}: the decoder may allocate at most {} (the texture limit of {MAX_TEXELS} \
             texels, 8192 x 8192, at 16 bytes a texel)",
            crate::memory::human(MAX_DECODER_BYTES)
        ),
        _ => e.to_string(),
    }
}

/// An empty vector with room for `n` values, or `None` when memory is short.
fn room_for<T>(n: usize) -> Option<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).ok().map(|_| v)
}

#[cfg(test)]
mod tests {
    use super::*;

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
            // A fully transparent texel keeps its color (straight alpha).
            (
                "rgba8.png",
                image::RgbaImage::from_pixel(1, 1, image::Rgba([128, 128, 128, 0])).into(),
                half8,
            ),
        ];
        for (name, img, encoded) in cases {
            let path = dir.join(name);
            img.save(&path).unwrap();
            let srgb = load_texture_image(&Files::disk(), &path, true, None).unwrap();
            let linear = load_texture_image(&Files::disk(), &path, false, None).unwrap();
            assert_eq!((srgb.width, srgb.height), (1, 1));
            for c in srgb.texels[0].to_array() {
                assert!((c - srgb_to_linear(encoded)).abs() < 1e-6, "{name}: {c}");
            }
            for c in linear.texels[0].to_array() {
                assert!((c - encoded).abs() < 1e-6, "{name}: {c}");
            }
            // Alpha is kept only where the file has it, as stored whatever the color space.
            let expected = name.starts_with("rgba").then(|| vec![0.0]);
            assert_eq!(srgb.alpha, expected, "{name}");
            assert_eq!(linear.alpha, expected, "{name}");
        }
        let corrupt = dir.join("corrupt.png");
        std::fs::write(&corrupt, b"not a png").unwrap();
        assert!(load_texture_image(&Files::disk(), &corrupt, true, None).is_err());
        assert!(load_texture_image(&Files::disk(), &dir.join("missing.png"), true, None).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn sound_palettes_decode_and_broken_ones_are_errors_not_panics() {
        let good = include_bytes!("../../../fuzz/corpus/texture/palette_2x2.png");
        let image = decode_texture_image(good, true, None).unwrap();
        assert_eq!((image.width, image.height), (2, 2));
        // A 262-byte palette with valid CRCs: png 0.18.1 alone panics on it.
        let bad =
            include_bytes!("../../../fuzz/regressions/texture/png_palette_not_whole_entries.png");
        let err = decode_texture_image(bad, true, None).unwrap_err();
        assert!(err.contains("PLTE chunk) has 262 bytes"), "{err}");
    }
}
