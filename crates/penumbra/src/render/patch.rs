//! Render settings changed per call: a [`SettingsPatch`] holds what a caller asks for (the
//! command line's flags, Python's keyword arguments) and applies it to a scene file's
//! [`RenderSettings`], by the one rule for a sampler chosen without a sample count.
//!
//! ```
//! use penumbra::{RenderSettings, Sampler, SettingsPatch};
//!
//! // A file that says `sampler = "grid"` and `samples = 16`.
//! let file = RenderSettings { sampler: Sampler::Grid, spp: 16, ..RenderSettings::default() };
//! let center = SettingsPatch { sampler: Some(Sampler::Center), ..SettingsPatch::default() };
//! assert_eq!(center.apply(&file, Some(16))?.spp, 1);
//! let jittered = SettingsPatch { sampler: Some(Sampler::Jittered), ..SettingsPatch::default() };
//! assert_eq!(jittered.apply(&file, Some(16))?.spp, 16);
//! # Ok::<(), penumbra::SettingsError>(())
//! ```

use super::settings::{RenderSettings, SettingsError, View};
use crate::integrator::{LightModel, Shading};
use crate::math::Rgb;
use crate::sampling::Sampler;

/// Changes to render settings: each field that is `Some` replaces the setting of that name,
/// `None` keeps it. `Default` changes nothing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SettingsPatch {
    /// The camera.
    pub view: Option<View>,
    /// Film width in pixels.
    pub width: Option<u32>,
    /// Film height in pixels.
    pub height: Option<u32>,
    /// Pixel sample pattern; without [`SettingsPatch::spp`] it takes its own count (see
    /// [`SettingsPatch::apply`]).
    pub sampler: Option<Sampler>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// N of every area light (N×N samples), replacing each light's own.
    pub light_samples: Option<u32>,
    /// Seed of every random choice.
    pub seed: Option<u64>,
    /// Specular lobe.
    pub shading: Option<Shading>,
    /// Light model.
    pub light_model: Option<LightModel>,
    /// Ambient light I_a.
    pub ambient: Option<Rgb>,
    /// Radiance of camera rays that hit nothing.
    pub background: Option<Rgb>,
    /// Coverage alpha (see [`RenderSettings::alpha`]).
    pub alpha: Option<bool>,
}

impl SettingsPatch {
    /// `base`, a scene file's settings, with this patch applied and checked (all but the view,
    /// which [`RenderSettings::check`] checks against a world). `file_samples` is the file's
    /// `render.samples`, when it gives one.
    ///
    /// A sampler without `spp` takes its own count ([`implied_spp`]): 1 for
    /// [`Sampler::Center`], its only count; else `file_samples`; else 4. An explicit `spp`
    /// always wins, and is refused with [`SettingsError::CenterSpp`] when it is not 1 for the
    /// center sampler, patched or the file's.
    pub fn apply(
        &self,
        base: &RenderSettings,
        file_samples: Option<u32>,
    ) -> Result<RenderSettings, SettingsError> {
        let mut s = base.clone();
        if let Some(view) = &self.view {
            s.view = view.clone();
        }
        s.width = self.width.unwrap_or(s.width);
        s.height = self.height.unwrap_or(s.height);
        if let Some(sampler) = self.sampler {
            s.sampler = sampler;
            s.spp = implied_spp(sampler, file_samples);
        }
        s.spp = self.spp.unwrap_or(s.spp);
        s.light_samples = self.light_samples.or(s.light_samples);
        s.seed = self.seed.unwrap_or(s.seed);
        s.shading = self.shading.unwrap_or(s.shading);
        s.light_model = self.light_model.unwrap_or(s.light_model);
        s.ambient = self.ambient.unwrap_or(s.ambient);
        s.background = self.background.unwrap_or(s.background);
        s.alpha = self.alpha.unwrap_or(s.alpha);
        s.check_values()?;
        Ok(s)
    }
}

/// Samples per pixel of `sampler` chosen without a count of its own: 1 for
/// [`Sampler::Center`], its only count; else `samples`, the count the scene file gives; else
/// the default, 4. A file's `sampler` without `samples`, an override of `render.sampler`
/// alone and a [`SettingsPatch`] (`--sampler`, Python's `sampler=`) all follow this one rule.
pub(crate) fn implied_spp(sampler: Sampler, samples: Option<u32>) -> u32 {
    match (sampler, samples) {
        (Sampler::Center, _) => 1,
        (_, Some(n)) => n,
        (_, None) => RenderSettings::default().spp,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler::{Center, Grid, Jittered, Rgss};

    /// The settings a file with `sampler` and `samples` builds (its sampler takes its own
    /// count when it gives none).
    fn file(sampler: Sampler, samples: Option<u32>) -> RenderSettings {
        RenderSettings {
            sampler,
            spp: implied_spp(sampler, samples),
            ..RenderSettings::default()
        }
    }

    /// A file's sampler and samples, a patch's sampler and spp, and the sampler and spp
    /// rendered (or the error).
    type Case = (
        (Sampler, Option<u32>),
        (Option<Sampler>, Option<u32>),
        Result<(Sampler, u32), SettingsError>,
    );

    #[test]
    fn a_sampler_without_spp_takes_its_own_count() {
        #[rustfmt::skip]
        let cases: &[Case] = &[
            // No samples in the file: 1 for center, else the default 4.
            ((Rgss, None), (Some(Center), None), Ok((Center, 1))),
            ((Rgss, None), (Some(Grid), None), Ok((Grid, 4))),
            ((Rgss, None), (Some(Rgss), None), Ok((Rgss, 4))),
            ((Rgss, None), (Some(Jittered), None), Ok((Jittered, 4))),
            ((Center, None), (Some(Jittered), None), Ok((Jittered, 4))),
            // The file's samples: the count of every sampler but center.
            ((Grid, Some(16)), (Some(Center), None), Ok((Center, 1))),
            ((Grid, Some(16)), (Some(Grid), None), Ok((Grid, 16))),
            ((Grid, Some(16)), (Some(Rgss), None), Ok((Rgss, 16))),
            ((Grid, Some(16)), (Some(Jittered), None), Ok((Jittered, 16))),
            ((Center, Some(1)), (Some(Grid), None), Ok((Grid, 1))),
            // An explicit spp wins, with or without a sampler.
            ((Grid, Some(16)), (Some(Jittered), Some(9)), Ok((Jittered, 9))),
            ((Rgss, None), (None, Some(9)), Ok((Rgss, 9))),
            ((Center, None), (Some(Rgss), Some(1)), Ok((Rgss, 1))),
            ((Center, None), (Some(Center), Some(1)), Ok((Center, 1))),
            // Nothing patched: the file's.
            ((Grid, Some(16)), (None, None), Ok((Grid, 16))),
            ((Center, None), (None, None), Ok((Center, 1))),
            // Refused: center with more than 1 sample, patched or the file's; no square.
            ((Rgss, None), (Some(Center), Some(4)), Err(SettingsError::CenterSpp)),
            ((Center, None), (None, Some(4)), Err(SettingsError::CenterSpp)),
            ((Rgss, None), (None, Some(3)), Err(SettingsError::Spp(3))),
            ((Rgss, None), (Some(Grid), Some(0)), Err(SettingsError::Spp(0))),
        ];
        for &((f_sampler, f_samples), (sampler, spp), ref want) in cases {
            let patch = SettingsPatch {
                sampler,
                spp,
                ..SettingsPatch::default()
            };
            let got = patch
                .apply(&file(f_sampler, f_samples), f_samples)
                .map(|s| (s.sampler, s.spp));
            assert_eq!(
                &got, want,
                "file {f_sampler:?} {f_samples:?}, patch {sampler:?} {spp:?}"
            );
        }
    }

    #[test]
    fn every_field_replaces_its_setting() {
        let base = RenderSettings::default();
        assert_eq!(
            SettingsPatch::default().apply(&base, None),
            Ok(base.clone())
        );
        let patch = SettingsPatch {
            view: Some(View::Named("high".into())),
            width: Some(32),
            height: Some(16),
            sampler: Some(Jittered),
            spp: Some(9),
            light_samples: Some(3),
            seed: Some(7),
            shading: Some(Shading::BlinnPhong),
            light_model: Some(LightModel::Physical),
            ambient: Some(Rgb::splat(0.5)),
            background: Some(Rgb::ONE),
            alpha: Some(true),
        };
        let want = RenderSettings {
            view: View::Named("high".into()),
            width: 32,
            height: 16,
            sampler: Jittered,
            spp: 9,
            light_samples: Some(3),
            seed: 7,
            shading: Shading::BlinnPhong,
            light_model: LightModel::Physical,
            ambient: Rgb::splat(0.5),
            background: Rgb::ONE,
            alpha: true,
        };
        assert_eq!(patch.apply(&base, None), Ok(want.clone()));
        // A patch of nothing keeps a base's light samples, views and colours.
        assert_eq!(SettingsPatch::default().apply(&want, Some(9)), Ok(want));
    }

    #[test]
    fn patched_values_are_checked_but_not_the_view() {
        let base = RenderSettings::default();
        let with = |p: SettingsPatch| p.apply(&base, None);
        assert_eq!(
            with(SettingsPatch {
                width: Some(0),
                ..SettingsPatch::default()
            }),
            Err(SettingsError::EmptyFilm {
                width: 0,
                height: 480
            })
        );
        assert_eq!(
            with(SettingsPatch {
                light_samples: Some(0),
                ..SettingsPatch::default()
            }),
            Err(SettingsError::LightSamples(0))
        );
        // No world to look the camera up in: a name is kept for `check` to refuse.
        let named = with(SettingsPatch {
            view: Some(View::Named("nowhere".into())),
            ..SettingsPatch::default()
        });
        assert_eq!(named.map(|s| s.view), Ok(View::Named("nowhere".into())));
    }
}
