//! The AOV files beside an image (see [`render_with_aovs`](crate::render_with_aovs) for the
//! passes), each pass's values as [`AovFilm::values`] gives them:
//!
//! - an EXR image: one multi-layer file instead of the colour-only one ([`stage_exr`]). The
//!   colour is `R`, `G`, `B` (premultiplied, with `A`, when the film has alpha); the passes are channels named as Blender and Mitsuba name them,
//!   one layer per pass: `depth.Z`, `normal.X/Y/Z`, `albedo.R/G/B`, `position.X/Y/Z` (32-bit
//!   floats) and `object_id`, `primitive_id` (32-bit unsigned integers, exact);
//! - any other image (`out.png`, `.jpg`, `.pfm`): one file per pass beside it
//!   ([`stage_pass_files`], named by [`pass_path`]): `out.depth.pfm`, `out.normal.pfm`, ...
//!   (float PFM: 1 channel for depth, 3 for the others) and `out.object_id.exr`,
//!   `out.primitive_id.exr` (a single 32-bit unsigned integer channel `Y`: every id is exact,
//!   which a float file could not promise above 2^24);
//! - Python's batches: every pass in one NumPy `.npz` beside the image ([`npz_path`],
//!   [`stage_npz`]).
//!
//! Each is staged ([`StagedFile`]); the caller renames them into place with the image.

use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, WritableImage,
};

use super::npz::{npz_bytes, NpyArray};
use super::ProductError;
use crate::film::Film;
use crate::image_error::ImageError;
use crate::image_format::OutputFormat;
use crate::image_io::check_finite;
use crate::render::{Aov, AovFilm, AovValues};
use crate::staged::StagedFile;

/// The channels of a float pass's layer in a multi-layer EXR (an id's layer is one unnamed
/// channel: none here).
pub fn layer_channels(p: Aov) -> &'static [&'static str] {
    match p {
        Aov::Depth | Aov::Z => &["Z"],
        Aov::Normal | Aov::Position => &["X", "Y", "Z"],
        Aov::Albedo => &["R", "G", "B"],
        Aov::ObjectId | Aov::PrimitiveId => &[],
    }
}

/// `out.png` with pass `p`: `out.depth.pfm`, or `out.object_id.exr` for ids.
pub fn pass_path(image: &Path, p: Aov) -> PathBuf {
    let stem = image.file_stem().unwrap_or_default().to_string_lossy();
    let ext = if p.is_id() { "exr" } else { "pfm" };
    image.with_file_name(format!("{stem}.{}.{ext}", p.name()))
}

/// Where Python's batches put the AOVs of the image at `image`: `out/a.png` →
/// `out/a.aovs.npz`.
pub fn npz_path(image: &Path) -> PathBuf {
    image.with_extension("aovs.npz")
}

/// The values of pass `p`, or an error when there is no memory for them.
fn values(aovs: &AovFilm, p: Aov) -> Result<AovValues, ProductError> {
    aovs.values(p).map_err(|_| ProductError::Memory(p.name()))
}

/// Stages the colour `film` and `passes` as one multi-layer EXR for `path`.
pub fn stage_exr(
    path: &Path,
    film: &Film,
    aovs: &AovFilm,
    passes: &[Aov],
) -> Result<StagedFile, ProductError> {
    check_finite(film, path, OutputFormat::Exr)?;
    let mut channels = Vec::new();
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let v = film.pixels.iter().map(|p| p[c]).collect();
        channels.push(AnyChannel::new(name, FlatSamples::F32(v)));
    }
    if let Some(alpha) = &film.alpha {
        channels.push(AnyChannel::new("A", FlatSamples::F32(alpha.clone())));
    }
    for &p in passes {
        match values(aovs, p)? {
            AovValues::Ids(v) => channels.push(AnyChannel::new(p.name(), FlatSamples::U32(v))),
            AovValues::Floats(v) => {
                let n = p.components();
                for (c, ch) in layer_channels(p).iter().enumerate() {
                    let plane = v.iter().skip(c).step_by(n).copied().collect();
                    let name = format!("{}.{ch}", p.name());
                    channels.push(AnyChannel::new(name.as_str(), FlatSamples::F32(plane)));
                }
            }
        }
    }
    let bytes = exr_bytes(film.width, film.height, channels).map_err(|m| write_error(path, m))?;
    Ok(StagedFile::write_bytes(path, &bytes)?)
}

/// Stages each of `passes` as its own file beside `image` (see [`pass_path`]), in order.
/// `cancel`, once set, stops the staging between files ([`ImageError::Cancelled`]).
pub fn stage_pass_files(
    image: &Path,
    aovs: &AovFilm,
    passes: &[Aov],
    cancel: &AtomicBool,
) -> Result<Vec<StagedFile>, ProductError> {
    let mut staged = Vec::with_capacity(passes.len());
    for &p in passes {
        let path = pass_path(image, p);
        let bytes = match values(aovs, p)? {
            AovValues::Ids(v) => {
                let channel = AnyChannel::new("Y", FlatSamples::U32(v));
                exr_bytes(aovs.width, aovs.height, vec![channel])
                    .map_err(|m| write_error(&path, m))?
            }
            AovValues::Floats(v) => pfm_bytes(aovs.width, aovs.height, p.components(), &v),
        };
        if cancel.load(Ordering::Relaxed) {
            return Err(ImageError::Cancelled.into());
        }
        staged.push(StagedFile::write_bytes(&path, &bytes)?);
    }
    Ok(staged)
}

/// Stages `arrays` (by name, in order) as the NumPy `.npz` at `path`, as `numpy.savez`
/// writes one: each array `NAME.npy` in an uncompressed ZIP.
pub fn stage_npz(path: &Path, arrays: &[(String, NpyArray)]) -> Result<StagedFile, ProductError> {
    let bytes = npz_bytes(arrays).map_err(|message| ProductError::Invalid {
        path: path.to_owned(),
        message,
    })?;
    Ok(StagedFile::write_bytes(path, &bytes)?)
}

fn write_error(path: &Path, message: String) -> ProductError {
    ImageError::Write {
        path: path.to_owned(),
        message,
    }
    .into()
}

/// An EXR of one layer holding `channels` (sorted by name, as the format wants), losslessly
/// compressed.
fn exr_bytes(
    width: u32,
    height: u32,
    channels: Vec<AnyChannel<FlatSamples>>,
) -> Result<Vec<u8>, String> {
    let size = (width as usize, height as usize);
    let layer = Layer::new(
        size,
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    let mut w = Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut w)
        .map_err(|e| format!("cannot encode EXR: {e}"))?;
    Ok(w.into_inner())
}

/// A Portable Float Map (`Pf` grey or `PF` colour, little-endian, rows bottom to top) of
/// `values`, `channels` per pixel, rows top to bottom.
fn pfm_bytes(width: u32, height: u32, channels: usize, values: &[f32]) -> Vec<u8> {
    let magic = if channels == 1 { "Pf" } else { "PF" };
    let mut out = format!("{magic}\n{width} {height}\n-1.0\n").into_bytes();
    let row = (width as usize * channels).max(1);
    for r in values.chunks(row).rev() {
        for v in r {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pass_files_sit_beside_the_image() {
        let p = Path::new("out/shot.png");
        assert_eq!(pass_path(p, Aov::Depth), Path::new("out/shot.depth.pfm"));
        assert_eq!(
            pass_path(p, Aov::ObjectId),
            Path::new("out/shot.object_id.exr")
        );
        assert_eq!(npz_path(p), Path::new("out/shot.aovs.npz"));
    }

    #[test]
    fn pfm_rows_go_bottom_to_top() {
        let b = pfm_bytes(1, 2, 1, &[1.0, 2.0]);
        let header = b"Pf\n1 2\n-1.0\n";
        assert_eq!(&b[..header.len()], header);
        assert_eq!(
            &b[header.len()..],
            [2.0f32.to_le_bytes(), 1.0f32.to_le_bytes()].concat()
        );
    }
}
