//! `--aov`: passes (arbitrary output variables) beside the colour image, from the library's
//! [`render_with_aovs`](penumbra::render_with_aovs); the files (a multi-layer EXR, or PFM and
//! id EXR files beside the image) are [`penumbra::products::aov_files`]'. On a miss: depth is
//! `+inf`, the others zero, both ids `4294967295` (`u32::MAX`).

use std::path::Path;

use penumbra::products::aov_files::{self, layer_channels};
use penumbra::products::ProductError;
use penumbra::{Aov, AovFilm, AovPixel, Film, ImageError, StagedFile, NO_ID};

use crate::failure::{invalid, runtime, Failure};
use crate::signals::Interrupt;

/// The channel names of `passes` as an EXR output names them (`depth.Z`, `normal.X`, …,
/// `object_id`), in order: what `--display-server` sends beside R, G and B.
pub fn channel_names(passes: &Passes) -> Vec<String> {
    let mut names = Vec::new();
    for &p in &passes.0 {
        match layer_channels(p) {
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

/// The failure of writing pass files.
fn failure(e: ProductError, interrupt: &Interrupt) -> Failure {
    match e {
        ProductError::Image(ImageError::Cancelled) => interrupt.failure(),
        e @ ProductError::Image(ImageError::NonFinite { .. }) => invalid(e),
        e => runtime(e),
    }
}

/// Stages the colour and `passes` as one multi-layer EXR for `path`.
pub fn stage_exr(
    path: &Path,
    film: &Film,
    aovs: &AovFilm,
    passes: &Passes,
    interrupt: &Interrupt,
) -> Result<StagedFile, Failure> {
    aov_files::stage_exr(path, film, aovs, &passes.0).map_err(|e| failure(e, interrupt))
}

/// Stages each of `passes` as its own file beside `image`, in the order of `passes`. A
/// signal stops the staging between files.
pub fn stage_files(
    image: &Path,
    aovs: &AovFilm,
    passes: &Passes,
    interrupt: &Interrupt,
) -> Result<Vec<StagedFile>, Failure> {
    aov_files::stage_pass_files(image, aovs, &passes.0, interrupt.flag())
        .map_err(|e| failure(e, interrupt))
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
}
