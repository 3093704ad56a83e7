//! The render flags as a [`SettingsPatch`] of the scene file's settings (the library applies
//! it, as it applies Python's keywords), the region to render, and the flag each settings
//! error is about.

use penumbra::{PixelBounds, RenderSettings, Sampler, SettingsError, SettingsPatch, View};

use crate::args::{CropWindow, RenderArgs};

/// The change the command line's flags make to the scene file's settings `base` (with
/// `--set`), looking through `camera` (`None`: the file's default); apply it with the file's
/// samples.
///
/// `--width`/`--height` (or `--resolution`), then `--quick` (a quarter of each side, as pbrt: `max(1, side / 4)`;
/// center sampling with 1 spp unless `--spp` is given, 1 light sample per area light), then
/// `--sampler`, `--spp`, `--light-samples`, `--seed` and `--alpha`.
pub fn patch(args: &RenderArgs, base: &RenderSettings, camera: Option<&str>) -> SettingsPatch {
    let (mut width, mut height) = match args.resolution {
        Some((w, h)) => (Some(w), Some(h)),
        None => (args.width, args.height),
    };
    let (mut sampler, mut light_samples) = (args.sampler, args.light_samples);
    if args.quick {
        let quarter = |side: Option<u32>, of: u32| Some((side.unwrap_or(of) / 4).max(1));
        width = quarter(width, base.width);
        height = quarter(height, base.height);
        // Center sampling is the preview's 1 sample: a count from --spp keeps the scene's
        // sampler instead, which center (1 sample only) would refuse.
        if args.spp.is_none() {
            sampler = sampler.or(Some(Sampler::Center));
        }
        light_samples = light_samples.or(Some(1));
    }
    SettingsPatch {
        view: camera.map(|name| View::Named(name.to_owned())),
        width,
        height,
        sampler,
        spp: args.spp,
        light_samples,
        seed: args.seed,
        alpha: args.alpha.then_some(true),
        ..SettingsPatch::default()
    }
}

/// The pixels to render: `--pixelbounds`, or `--cropwindow` over this film; `None`: all.
pub fn region(args: &RenderArgs, s: &RenderSettings) -> Option<PixelBounds> {
    args.pixelbounds
        .or_else(|| args.cropwindow.map(|c| crop_bounds(c, s.width, s.height)))
}

/// pbrt-v4's mapping of a crop window to pixels: each bound is `ceil(resolution · fraction)`
/// in single precision, so adjacent windows share no pixel and leave none out. The result
/// may be empty; rendering then reports it as a bad region.
pub fn crop_bounds(c: CropWindow, width: u32, height: u32) -> PixelBounds {
    let at = |size: u32, f: f32| (size as f32 * f).ceil() as u32;
    PixelBounds {
        x0: at(width, c.x0),
        x1: at(width, c.x1),
        y0: at(height, c.y0),
        y1: at(height, c.y1),
    }
}

/// The flag a settings error is about, as the user typed it.
pub fn flag_of(e: &SettingsError) -> &'static str {
    match e {
        SettingsError::Spp(_) | SettingsError::CenterSpp => "--spp",
        SettingsError::LightSamples(_) => "--light-samples",
        SettingsError::EmptyFilm { .. } | SettingsError::FilmTooLarge { .. } => "--width/--height",
        SettingsError::UnknownCamera { .. } | SettingsError::NoCamera => "--camera",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crop_windows_round_up_like_pbrt() {
        let c = |x0, x1, y0, y1| CropWindow { x0, x1, y0, y1 };
        let b = crop_bounds(c(0.0, 1.0, 0.0, 1.0), 640, 480);
        assert_eq!((b.x0, b.x1, b.y0, b.y1), (0, 640, 0, 480));
        // 0.25·10 = 2.5 → 3; 0.5·10 = 5; 0.1·7 = 0.7 → 1; 0.9·7 = 6.3 → 7.
        let b = crop_bounds(c(0.25, 0.5, 0.1, 0.9), 10, 7);
        assert_eq!((b.x0, b.x1, b.y0, b.y1), (3, 5, 1, 7));
        // Two halves tile the film exactly.
        let (l, r) = (
            crop_bounds(c(0.0, 0.5, 0.0, 1.0), 9, 9),
            crop_bounds(c(0.5, 1.0, 0.0, 1.0), 9, 9),
        );
        assert_eq!((l.x1, r.x0, r.x1), (5, 5, 9));
    }
}
