//! The render flags applied to the scene file's settings, and the flag each settings error is
//! about.

use std::path::{Path, PathBuf};

use penumbra::{RenderSettings, Sampler, Scene, SceneFile, SettingsError, View};

use crate::args::{RenderArgs, SamplerArg};

/// The scene file's settings with the command line's flags applied.
pub fn settings(args: &RenderArgs, file: &SceneFile, scene: &Scene) -> RenderSettings {
    let mut s = scene.settings.clone();
    if let Some(w) = args.width {
        s.width = w;
    }
    if let Some(h) = args.height {
        s.height = h;
    }
    if let Some(sampler) = args.sampler {
        s.sampler = match sampler {
            SamplerArg::Center => Sampler::Center,
            SamplerArg::Grid => Sampler::Grid,
            SamplerArg::Rgss => Sampler::Rgss,
            SamplerArg::Jittered => Sampler::Jittered,
        };
        // A sampler without --spp takes its own default count: 1 for center, else the
        // file's `samples`, else 4.
        s.spp = match (s.sampler, file.desc.render.samples) {
            (Sampler::Center, _) => 1,
            (_, Some(n)) => u32::try_from(n).unwrap_or(u32::MAX),
            (_, None) => 4,
        };
    }
    if let Some(spp) = args.spp {
        s.spp = spp;
    }
    if args.light_samples.is_some() {
        s.light_samples = args.light_samples;
    }
    if let Some(seed) = args.seed {
        s.seed = seed;
    }
    if let Some(name) = &args.camera {
        s.view = View::Named(name.clone());
    }
    s
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

/// Where the image goes: `-o`, else `film.output`, else `<scene stem>.png` beside the scene.
pub fn output_path(args: &RenderArgs, scene: &Scene) -> PathBuf {
    if let Some(o) = &args.output {
        return o.clone();
    }
    if let Some(o) = &scene.output {
        return o.clone();
    }
    let stem = args.scene.file_stem().unwrap_or_default();
    args.scene
        .with_file_name(Path::new(stem).with_extension("png"))
}
