//! `[[lights]]`: one struct per kind, chosen by the table's `type` key (read by `tagged`).

use serde::de::{Deserializer, MapAccess};
use serde::Deserialize;

use super::tagged::{self, Tagged};
use super::values::{ColorDesc, Num, Vec3Desc};

/// `[[lights]]`, by its `type`. Lights are not geometry: camera rays do not see them and they
/// cast no shadows.
#[derive(Clone, Debug, PartialEq)]
pub enum LightDesc {
    /// `type = "area"`: the parallelogram `center ± u/2 ± v/2`, sampled on an N×N grid.
    Area(AreaLightDesc),
    /// `type = "point"`.
    Point(PointLightDesc),
}

/// An area light.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaLightDesc {
    /// Center.
    pub center: Vec3Desc,
    /// First edge.
    pub u: Vec3Desc,
    /// Second edge.
    pub v: Vec3Desc,
    /// Color (default 1).
    pub color: Option<ColorDesc>,
    /// Scale of the color (default 1).
    pub intensity: Option<Num>,
    /// N (default `render.light_samples`).
    pub samples: Option<i64>,
    /// One random point per cell instead of the cell centers.
    pub jitter: Option<bool>,
}

/// A point light.
#[derive(Clone, Debug, PartialEq)]
pub struct PointLightDesc {
    /// Where it is.
    pub position: Vec3Desc,
    /// Color (default 1).
    pub color: Option<ColorDesc>,
    /// Scale of the color (default 1).
    pub intensity: Option<Num>,
}

/// The `type` of a light.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum LightType {
    /// Parallelogram area light.
    Area,
    /// Point light.
    Point,
}

#[derive(Default)]
pub(super) struct LightFields {
    color: Option<ColorDesc>,
    intensity: Option<Num>,
    center: Option<Vec3Desc>,
    u: Option<Vec3Desc>,
    v: Option<Vec3Desc>,
    samples: Option<i64>,
    jitter: Option<bool>,
    position: Option<Vec3Desc>,
}

impl Tagged for LightDesc {
    type Kind = LightType;
    type Fields = LightFields;
    const COMMON: &'static [&'static str] = &["color", "intensity"];
    const ALL: &'static [&'static str] = &["center", "u", "v", "samples", "jitter", "position"];

    const KINDS: &'static [LightType] = &[LightType::Area, LightType::Point];

    fn keys(kind: LightType) -> &'static [&'static str] {
        match kind {
            LightType::Area => &["center", "u", "v", "samples", "jitter"],
            LightType::Point => &["position"],
        }
    }

    fn describe(kind: LightType) -> &'static str {
        match kind {
            LightType::Area => "an area light",
            LightType::Point => "a point light",
        }
    }

    fn read<'de, A: MapAccess<'de>>(
        f: &mut LightFields,
        key: &str,
        map: &mut A,
    ) -> Result<(), A::Error> {
        match key {
            "color" => f.color = Some(map.next_value()?),
            "intensity" => f.intensity = Some(map.next_value()?),
            "center" => f.center = Some(map.next_value()?),
            "u" => f.u = Some(map.next_value()?),
            "v" => f.v = Some(map.next_value()?),
            "samples" => f.samples = Some(map.next_value()?),
            "jitter" => f.jitter = Some(map.next_value()?),
            _ => f.position = Some(map.next_value()?),
        }
        Ok(())
    }

    fn finish(kind: LightType, f: LightFields) -> Result<Self, &'static str> {
        Ok(match kind {
            LightType::Area => LightDesc::Area(AreaLightDesc {
                center: f.center.ok_or("center")?,
                u: f.u.ok_or("u")?,
                v: f.v.ok_or("v")?,
                color: f.color,
                intensity: f.intensity,
                samples: f.samples,
                jitter: f.jitter,
            }),
            LightType::Point => LightDesc::Point(PointLightDesc {
                position: f.position.ok_or("position")?,
                color: f.color,
                intensity: f.intensity,
            }),
        })
    }
}

impl<'de> Deserialize<'de> for LightDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        tagged::deserialize(d)
    }
}
