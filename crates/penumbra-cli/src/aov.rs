//! `--aov`: passes (arbitrary output variables) beside the colour image, from the library's
//! [`render_with_aovs`](penumbra::render_with_aovs) (see its module for how each is filtered).
//!
//! Where they go:
//! - EXR output: one multi-layer file instead of the colour-only one. The colour is `R`, `G`,
//!   `B`; the passes are channels named as Blender and Mitsuba name them, one layer per pass:
//!   `depth.Z`, `normal.X/Y/Z`, `albedo.R/G/B`, `position.X/Y/Z` (32-bit floats) and
//!   `object_id`, `primitive_id` (32-bit unsigned integers, exact).
//! - Any other output (`out.png`, `.jpg`, `.pfm`): one file per pass beside the image, named by
//!   its stem and the pass: `out.depth.pfm`, `out.normal.pfm`, `out.albedo.pfm`,
//!   `out.position.pfm` (float PFM: 1 channel for depth, 3 for the others) and
//!   `out.object_id.exr`, `out.primitive_id.exr` (a single 32-bit unsigned integer channel `Y`:
//!   every id is exact, which a float file could not promise above 2^24).
//!
//! On a miss: depth is `+inf`, the others zero, both ids `4294967295` (`u32::MAX`). Every file
//! appears complete or not at all (a temporary file renamed into place).

use std::fs::File;
use std::io::{Cursor, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, WritableImage,
};
use penumbra::{AovFilm, AovPixel, Film, ImageError};

use crate::failure::{invalid, runtime, Failure};
use crate::signals::Interrupt;

/// One pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    Depth,
    Normal,
    Albedo,
    Position,
    ObjectId,
    PrimitiveId,
}

/// Every pass, in the order files and channels list them.
pub const ALL: [Pass; 6] = [
    Pass::Depth,
    Pass::Normal,
    Pass::Albedo,
    Pass::Position,
    Pass::ObjectId,
    Pass::PrimitiveId,
];

impl Pass {
    /// Its name on the command line, in file names and in EXR layer names.
    pub fn name(self) -> &'static str {
        match self {
            Pass::Depth => "depth",
            Pass::Normal => "normal",
            Pass::Albedo => "albedo",
            Pass::Position => "position",
            Pass::ObjectId => "object_id",
            Pass::PrimitiveId => "primitive_id",
        }
    }

    /// The channels of its layer in a multi-layer EXR.
    fn channels(self) -> &'static [&'static str] {
        match self {
            Pass::Depth => &["Z"],
            Pass::Normal | Pass::Position => &["X", "Y", "Z"],
            Pass::Albedo => &["R", "G", "B"],
            Pass::ObjectId | Pass::PrimitiveId => &[],
        }
    }

    /// The float values of channel `c` of one pixel (not for ids).
    fn float(self, p: &AovPixel, c: usize) -> f32 {
        match self {
            Pass::Depth => p.depth,
            Pass::Normal => p.normal[c],
            Pass::Albedo => p.albedo[c],
            Pass::Position => p.position[c],
            Pass::ObjectId | Pass::PrimitiveId => id_of(p, self) as f32,
        }
    }

    fn is_id(self) -> bool {
        matches!(self, Pass::ObjectId | Pass::PrimitiveId)
    }
}

/// The id pass `pass` of one pixel.
fn id_of(px: &AovPixel, pass: Pass) -> u32 {
    if pass == Pass::ObjectId {
        px.object_id
    } else {
        px.primitive_id
    }
}

/// The passes `--aov` asks for, without repeats, in [`ALL`]'s order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Passes(pub Vec<Pass>);

/// Parses `--aov`: a comma list of pass names, or `all`.
pub fn parse(s: &str) -> Result<Passes, String> {
    let mut wanted = Vec::new();
    for item in s.split(',').map(str::trim) {
        if item == "all" {
            wanted.extend(ALL);
            continue;
        }
        match ALL.iter().find(|p| p.name() == item) {
            Some(&p) => wanted.push(p),
            None => {
                let names: Vec<&str> = ALL.iter().map(|p| p.name()).collect();
                return Err(format!(
                    "unknown pass `{item}` (known: {}, or all)",
                    names.join(", ")
                ));
            }
        }
    }
    Ok(Passes(
        ALL.into_iter().filter(|p| wanted.contains(p)).collect(),
    ))
}

/// `out.png` with pass `p`: `out.depth.pfm`, or `out.object_id.exr` for ids.
pub fn pass_path(image: &Path, p: Pass) -> PathBuf {
    let stem = image.file_stem().unwrap_or_default().to_string_lossy();
    let ext = if p.is_id() { "exr" } else { "pfm" };
    image.with_file_name(format!("{stem}.{}.{ext}", p.name()))
}

/// Writes the colour and `passes` into one multi-layer EXR at `path`.
pub fn write_exr(
    path: &Path,
    film: &Film,
    aovs: &AovFilm,
    passes: &Passes,
    interrupt: &Interrupt,
) -> Result<(), Failure> {
    if let Some((i, value)) = film.pixels.iter().enumerate().find_map(|(i, p)| {
        let v = p.to_array().into_iter().find(|c| !c.is_finite())?;
        Some((i, v))
    }) {
        let width = film.width.max(1) as usize;
        return Err(invalid(ImageError::NonFinite {
            path: path.to_owned(),
            x: (i % width) as u32,
            y: (i / width) as u32,
            value,
        }));
    }
    let mut channels = Vec::new();
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let v = film.pixels.iter().map(|p| p[c]).collect();
        channels.push(AnyChannel::new(name, FlatSamples::F32(v)));
    }
    for &p in &passes.0 {
        if p.is_id() {
            let v = aovs.pixels.iter().map(|px| id_of(px, p)).collect();
            channels.push(AnyChannel::new(p.name(), FlatSamples::U32(v)));
        }
        for (c, ch) in p.channels().iter().enumerate() {
            let v = aovs.pixels.iter().map(|px| p.float(px, c)).collect();
            let name = format!("{}.{ch}", p.name());
            channels.push(AnyChannel::new(name.as_str(), FlatSamples::F32(v)));
        }
    }
    let bytes = exr_bytes(film.width, film.height, channels).map_err(runtime)?;
    write_atomic(path, &bytes, interrupt)
}

/// Writes each of `passes` to its own file beside `image` (see [`pass_path`]); returns the
/// files written, in the order of `passes`.
pub fn write_files(
    image: &Path,
    aovs: &AovFilm,
    passes: &Passes,
    interrupt: &Interrupt,
) -> Result<Vec<PathBuf>, Failure> {
    let mut written = Vec::with_capacity(passes.0.len());
    for &p in &passes.0 {
        let bytes = if p.is_id() {
            let v = aovs.pixels.iter().map(|px| id_of(px, p)).collect();
            let channel = AnyChannel::new("Y", FlatSamples::U32(v));
            exr_bytes(aovs.width, aovs.height, vec![channel]).map_err(runtime)?
        } else {
            let n = if p == Pass::Depth { 1 } else { 3 };
            let v: Vec<f32> = aovs
                .pixels
                .iter()
                .flat_map(|px| (0..n).map(move |c| p.float(px, c)))
                .collect();
            pfm_bytes(aovs.width, aovs.height, n, &v)
        };
        let path = pass_path(image, p);
        write_atomic(&path, &bytes, interrupt)?;
        written.push(path);
    }
    Ok(written)
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

/// Writes `bytes` to `path` through a temporary file in the same folder, renamed into place
/// unless a signal arrived meanwhile.
fn write_atomic(path: &Path, bytes: &[u8], interrupt: &Interrupt) -> Result<(), Failure> {
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
    let result = File::create(&tmp)
        .and_then(|mut f| f.write_all(bytes).and_then(|()| f.sync_all()))
        .map_err(|e| e.to_string())
        .and_then(|()| {
            if interrupt.flag().load(Ordering::SeqCst) {
                return Err("interrupted".to_owned());
            }
            std::fs::rename(&tmp, path).map_err(|e| e.to_string())
        });
    result.map_err(|message| {
        let _ = std::fs::remove_file(&tmp);
        if interrupt.flag().load(Ordering::SeqCst) {
            interrupt.failure()
        } else {
            runtime(format!("{}: cannot write image: {message}", path.display()))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_parse_in_a_fixed_order_without_repeats() {
        assert_eq!(
            parse("normal, depth,normal").unwrap(),
            Passes(vec![Pass::Depth, Pass::Normal])
        );
        assert_eq!(parse("all").unwrap(), Passes(ALL.to_vec()));
        let e = parse("depth,zdepth").unwrap_err();
        assert!(e.contains("unknown pass `zdepth`"), "{e}");
        assert!(e.contains("primitive_id"), "{e}");
    }

    #[test]
    fn pass_files_sit_beside_the_image() {
        let p = Path::new("out/shot.png");
        assert_eq!(pass_path(p, Pass::Depth), Path::new("out/shot.depth.pfm"));
        assert_eq!(
            pass_path(p, Pass::ObjectId),
            Path::new("out/shot.object_id.exr")
        );
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
