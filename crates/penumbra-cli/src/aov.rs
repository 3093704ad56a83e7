//! `--aov`: passes (arbitrary output variables) beside the colour image, from the library's
//! [`render_with_aovs`](penumbra::render_with_aovs) (see its module for how each is filtered),
//! each pass's values as [`AovFilm::values`] gives them (Python's arrays hold the same).
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
//! On a miss: depth is `+inf`, the others zero, both ids `4294967295` (`u32::MAX`). The image
//! and its pass files appear together or not at all: each is staged under a temporary name
//! ([`StagedFile`]) and all are renamed into place once every one is written.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, WritableImage,
};
use penumbra::{
    check_finite, Aov, AovFilm, AovPixel, AovValues, Film, OutputFormat, StagedFile, NO_ID,
};

use crate::failure::{invalid, runtime, Failure};
use crate::signals::Interrupt;

/// The channels of a float pass's layer in a multi-layer EXR (an id's layer is one unnamed
/// channel).
fn channels(p: Aov) -> &'static [&'static str] {
    match p {
        Aov::Depth | Aov::Z => &["Z"],
        Aov::Normal | Aov::Position => &["X", "Y", "Z"],
        Aov::Albedo => &["R", "G", "B"],
        Aov::ObjectId | Aov::PrimitiveId => &[],
    }
}

/// The channel names of `passes` as an EXR output names them (`depth.Z`, `normal.X`, …,
/// `object_id`), in order: what `--display-server` sends beside R, G and B.
pub fn channel_names(passes: &Passes) -> Vec<String> {
    let mut names = Vec::new();
    for &p in &passes.0 {
        match channels(p) {
            [] => names.push(p.name().to_owned()),
            chs => names.extend(chs.iter().map(|ch| format!("{}.{ch}", p.name()))),
        }
    }
    names
}

/// Appends the values of `passes` for one pixel, in [`channel_names`]' order, as floats (an
/// id as its number, −1 for none).
pub fn push_values(passes: &Passes, px: &AovPixel, out: &mut Vec<f32>) {
    let id = |v: u32| if v == NO_ID { -1.0 } else { v as f32 };
    for &p in &passes.0 {
        match p {
            Aov::Depth => out.push(px.depth),
            Aov::Z => out.push(px.z),
            Aov::Normal => out.extend(px.normal.to_array()),
            Aov::Albedo => out.extend(px.albedo.to_array()),
            Aov::Position => out.extend(px.position.to_array()),
            Aov::ObjectId => out.push(id(px.object_id)),
            Aov::PrimitiveId => out.push(id(px.primitive_id)),
        }
    }
}

/// The passes `--aov` asks for, without repeats, in [`Aov::ALL`]'s order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Passes(pub Vec<Aov>);

/// Parses `--aov`: a comma list of pass names, or `all`.
pub fn parse(s: &str) -> Result<Passes, String> {
    let mut wanted = Vec::new();
    for item in s.split(',').map(str::trim) {
        if item == "all" {
            wanted.extend(Aov::ALL);
            continue;
        }
        match item.parse::<Aov>() {
            Ok(p) => wanted.push(p),
            Err(e) => {
                return Err(format!(
                    "unknown pass `{item}` (known: {}, or all)",
                    e.known.join(", ")
                ));
            }
        }
    }
    Ok(Passes(
        Aov::ALL
            .into_iter()
            .filter(|p| wanted.contains(p))
            .collect(),
    ))
}

/// The values of pass `p`, or a runtime failure when there is no memory for them.
fn values(aovs: &AovFilm, p: Aov) -> Result<AovValues, Failure> {
    aovs.values(p)
        .map_err(|_| runtime(format!("not enough memory for the {} pass", p.name())))
}

/// `out.png` with pass `p`: `out.depth.pfm`, or `out.object_id.exr` for ids.
pub fn pass_path(image: &Path, p: Aov) -> PathBuf {
    let stem = image.file_stem().unwrap_or_default().to_string_lossy();
    let ext = if p.is_id() { "exr" } else { "pfm" };
    image.with_file_name(format!("{stem}.{}.{ext}", p.name()))
}

/// Stages the colour and `passes` as one multi-layer EXR for `path`.
pub fn stage_exr(
    path: &Path,
    film: &Film,
    aovs: &AovFilm,
    passes: &Passes,
) -> Result<StagedFile, Failure> {
    check_finite(film, path, OutputFormat::Exr).map_err(invalid)?;
    let mut channels = Vec::new();
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let v = film.pixels.iter().map(|p| p[c]).collect();
        channels.push(AnyChannel::new(name, FlatSamples::F32(v)));
    }
    for &p in &passes.0 {
        match values(aovs, p)? {
            AovValues::Ids(v) => channels.push(AnyChannel::new(p.name(), FlatSamples::U32(v))),
            AovValues::Floats(v) => {
                let n = p.components();
                for (c, ch) in self::channels(p).iter().enumerate() {
                    let plane = v.iter().skip(c).step_by(n).copied().collect();
                    let name = format!("{}.{ch}", p.name());
                    channels.push(AnyChannel::new(name.as_str(), FlatSamples::F32(plane)));
                }
            }
        }
    }
    let bytes = exr_bytes(film.width, film.height, channels).map_err(runtime)?;
    StagedFile::write_bytes(path, &bytes).map_err(runtime)
}

/// Stages each of `passes` as its own file beside `image` (see [`pass_path`]), in the order
/// of `passes`. A signal stops the staging between files.
pub fn stage_files(
    image: &Path,
    aovs: &AovFilm,
    passes: &Passes,
    interrupt: &Interrupt,
) -> Result<Vec<StagedFile>, Failure> {
    let mut staged = Vec::with_capacity(passes.0.len());
    for &p in &passes.0 {
        let bytes = match values(aovs, p)? {
            AovValues::Ids(v) => {
                let channel = AnyChannel::new("Y", FlatSamples::U32(v));
                exr_bytes(aovs.width, aovs.height, vec![channel]).map_err(runtime)?
            }
            AovValues::Floats(v) => pfm_bytes(aovs.width, aovs.height, p.components(), &v),
        };
        interrupt.check()?;
        staged.push(StagedFile::write_bytes(&pass_path(image, p), &bytes).map_err(runtime)?);
    }
    Ok(staged)
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
    fn lists_parse_in_a_fixed_order_without_repeats() {
        assert_eq!(
            parse("normal, depth,normal").unwrap(),
            Passes(vec![Aov::Depth, Aov::Normal])
        );
        assert_eq!(parse("all").unwrap(), Passes(Aov::ALL.to_vec()));
        let e = parse("depth,zdepth").unwrap_err();
        assert_eq!(
            e,
            "unknown pass `zdepth` (known: depth, normal, albedo, position, object_id, primitive_id, z, or all)"
        );
        // `range` is the distance along the ray: depth.
        assert_eq!(parse("range,z").unwrap(), Passes(vec![Aov::Depth, Aov::Z]));
    }

    #[test]
    fn pass_files_sit_beside_the_image() {
        let p = Path::new("out/shot.png");
        assert_eq!(pass_path(p, Aov::Depth), Path::new("out/shot.depth.pfm"));
        assert_eq!(
            pass_path(p, Aov::ObjectId),
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
