//! Radiance `.hdr` files whose scanlines are flat: Radiance writes a scanline shorter than 8 or
//! longer than 32767 texels without run-length encoding (`fwritecolrs`) and reads such widths
//! without looking for it (`freadcolrs` goes to `oldreadcolrs`). The `image` crate looks for it
//! at every width, so a flat scanline that starts with a texel of 2, 2 and less than 128 is
//! misread as an encoded one and refused. Other widths are left to the `image` crate.

use std::io::Cursor;

use image::codecs::hdr::HdrDecoder;
use image::{ImageDecoder, Rgb32FImage};

/// True for a width whose scanlines Radiance writes flat.
fn is_flat(width: u32) -> bool {
    !(8..=0x7fff).contains(&width)
}

/// The texels of the Radiance file `bytes` when its width is flat (`None` otherwise, and for
/// an empty image), decoded as the `image` crate decodes RGBE (`c · 2^(e − 136)`, 0 for
/// `e = 0`). The header is the `image` crate's to read.
pub(super) fn decode(bytes: &[u8]) -> Option<Result<Rgb32FImage, String>> {
    let mut cursor = Cursor::new(bytes);
    let (width, height) = match HdrDecoder::new(&mut cursor) {
        Ok(header) => header.dimensions(),
        Err(e) => return Some(Err(e.to_string())),
    };
    if !is_flat(width) || width == 0 || height == 0 {
        return None;
    }
    let mut data = &bytes[cursor.position() as usize..];
    let (w, h) = (width as usize, height as usize);
    let texels = w * h;
    // Four bytes a texel at least (a run marker stands for more): a file too short is
    // refused before the texels are allocated.
    if data.len() / 4 < h {
        return Some(Err(format!(
            "the file ends early: {height} scanlines need at least {} bytes, {} are left",
            4 * h,
            data.len()
        )));
    }
    let mut floats = Vec::new();
    if floats.try_reserve_exact(texels * 3).is_err() {
        return Some(Err(format!(
            "not enough memory for a {width}x{height} image"
        )));
    }
    for row in 0..h {
        match scanline(&mut data, w, &mut floats) {
            Ok(()) => {}
            Err(e) => return Some(Err(format!("scanline {row}: {e}"))),
        }
    }
    Some(Rgb32FImage::from_raw(width, height, floats).ok_or_else(|| "bad image size".into()))
}

/// Reads one flat scanline of `width` texels from `data` into `out` (three floats a texel):
/// RGBE texels, where a texel (1, 1, 1, n) repeats the previous one n times, shifted left by 8
/// bits for each marker right before it (Radiance's `oldreadcolrs`).
fn scanline(data: &mut &[u8], width: usize, out: &mut Vec<f32>) -> Result<(), String> {
    let mut done = 0;
    let mut shift = 0u32;
    let mut previous: Option<[u8; 4]> = None;
    while done < width {
        let Some((texel, rest)) = data.split_first_chunk::<4>() else {
            return Err(format!("the file ends after {done} of its {width} texels"));
        };
        *data = rest;
        let texel = *texel;
        if texel[..3] == [1, 1, 1] {
            let Some(repeated) = previous else {
                return Err("it starts with a run marker (1, 1, 1), with nothing to repeat".into());
            };
            let run = (texel[3] as usize)
                .checked_shl(shift)
                .filter(|&n| n <= width - done && shift < 32)
                .ok_or_else(|| format!("a run goes past the end of its {width} texels"))?;
            for _ in 0..run {
                out.extend(rgbe(repeated));
            }
            done += run;
            shift += 8;
        } else {
            out.extend(rgbe(texel));
            previous = Some(texel);
            done += 1;
            shift = 0;
        }
    }
    Ok(())
}

/// The linear RGB of an RGBE texel, exactly as the `image` crate decodes it.
fn rgbe([r, g, b, e]: [u8; 4]) -> [f32; 3] {
    if e == 0 {
        return [0.0; 3];
    }
    let scale = 2f64.powi(i32::from(e) - 136);
    [r, g, b].map(|c| (f64::from(c) * scale) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Radiance file of `width × height` with these scanline bytes.
    fn file(width: u32, height: u32, body: &[u8]) -> Vec<u8> {
        let mut bytes =
            format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n").into_bytes();
        bytes.extend(body);
        bytes
    }

    #[test]
    fn flat_scanlines_decode_even_where_a_texel_looks_like_an_encoding() {
        // 4 × 2, the first texel (2, 2, 100, 129): what the `image` crate takes for the start
        // of a run-length encoded scanline.
        let texels: [[u8; 4]; 8] = [
            [2, 2, 100, 129],
            [128, 64, 32, 129],
            [255, 255, 255, 255],
            [0, 0, 0, 0],
            [10, 20, 30, 120],
            [1, 2, 3, 136],
            [128, 128, 128, 128],
            [50, 60, 70, 140],
        ];
        let bytes = file(4, 2, texels.as_flattened());
        assert!(
            image::load_from_memory(&bytes).is_err(),
            "the image crate reads it now"
        );
        let img = decode(&bytes).unwrap().unwrap();
        assert_eq!(img.dimensions(), (4, 2));
        let got: Vec<[f32; 3]> = img.pixels().map(|p| p.0).collect();
        assert_eq!(got[0], [2.0 / 128.0, 2.0 / 128.0, 100.0 / 128.0]);
        assert_eq!(got[1], [1.0, 0.5, 0.25]);
        assert_eq!(got[2][0], 255.0 * 2f32.powi(119));
        assert_eq!(got[3], [0.0; 3]);
        assert_eq!(got[5], [1.0, 2.0, 3.0]);
        assert_eq!(got[6], [0.5; 3]);
    }

    #[test]
    fn old_runs_repeat_and_broken_scanlines_are_errors() {
        // 3 wide: a texel and a run of 2.
        let img = decode(&file(3, 1, &[128, 0, 0, 129, 1, 1, 1, 2]))
            .unwrap()
            .unwrap();
        assert!(img.pixels().all(|p| p.0 == [1.0, 0.0, 0.0]));
        let bad: [&[u8]; 3] = [
            &[1, 1, 1, 2, 0, 0, 0, 0],
            &[128, 0, 0, 129, 1, 1, 1, 5],
            &[128, 0, 0, 129],
        ];
        for body in bad {
            let got = decode(&file(3, 1, body)).unwrap();
            assert!(got.is_err(), "{body:?}");
        }
        // Widths the `image` crate reads are left to it.
        assert!(decode(&file(8, 1, &[0; 32])).is_none());
    }
}
