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
    /// `type = "environment"`: radiance from every direction at infinity, from an
    /// equirectangular map or one color.
    Environment(EnvironmentLightDesc),
    /// `type = "directional"`: light from one direction at infinity (the sun).
    Directional(DirectionalLightDesc),
    /// `type = "spot"`: a point shining into a cone.
    Spot(SpotLightDesc),
}

/// A directional light.
#[derive(Clone, Debug, PartialEq)]
pub struct DirectionalLightDesc {
    /// The direction the light travels (toward the scene), as Mitsuba's `directional`.
    pub direction: Vec3Desc,
    /// Color (default 1).
    pub color: Option<ColorDesc>,
    /// Irradiance on a surface facing the light, a scale of the color (default 1).
    pub intensity: Option<Num>,
    /// Angular diameter in degrees (default 0: a point-like sun, hard shadows).
    pub angle: Option<Num>,
    /// N: N×N samples over the cone when `angle` > 0 (default `render.light_samples`).
    pub samples: Option<i64>,
}

/// A spot light.
#[derive(Clone, Debug, PartialEq)]
pub struct SpotLightDesc {
    /// Where it is.
    pub position: Vec3Desc,
    /// Where its cone points.
    pub direction: Vec3Desc,
    /// Color (default 1).
    pub color: Option<ColorDesc>,
    /// Scale of the color, in the units of a point light's (default 1).
    pub intensity: Option<Num>,
    /// Half-angle of full intensity, in degrees (default 0).
    pub inner_angle: Option<Num>,
    /// Half-angle beyond which nothing is sent, in degrees (default 45, at most 90).
    pub outer_angle: Option<Num>,
}

/// An environment light.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentLightDesc {
    /// The equirectangular map (Radiance HDR, OpenEXR linear; PNG, JPEG sRGB: by content),
    /// relative to the scene file's folder; exclusive with `color`.
    pub file: Option<String>,
    /// One radiance in every direction, instead of a file.
    pub color: Option<ColorDesc>,
    /// Scale on the radiance (default 1).
    pub intensity: Option<Num>,
    /// Degrees about +y (default 0).
    pub rotation: Option<Num>,
    /// N: N×N samples per shading point (default `render.light_samples`).
    pub samples: Option<i64>,
    /// Whether camera rays that miss see it (default true).
    pub visible: Option<bool>,
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
    /// Environment map.
    Environment,
    /// Directional light (sun).
    Directional,
    /// Spot light.
    Spot,
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
    file: Option<String>,
    rotation: Option<Num>,
    visible: Option<bool>,
    direction: Option<Vec3Desc>,
    angle: Option<Num>,
    inner_angle: Option<Num>,
    outer_angle: Option<Num>,
}

impl Tagged for LightDesc {
    type Kind = LightType;
    type Fields = LightFields;
    const COMMON: &'static [&'static str] = &["color", "intensity"];
    const ALL: &'static [&'static str] = &[
        "center",
        "u",
        "v",
        "samples",
        "jitter",
        "position",
        "file",
        "rotation",
        "visible",
        "direction",
        "angle",
        "inner_angle",
        "outer_angle",
    ];

    const KINDS: &'static [LightType] = &[
        LightType::Area,
        LightType::Point,
        LightType::Environment,
        LightType::Directional,
        LightType::Spot,
    ];

    fn keys(kind: LightType) -> &'static [&'static str] {
        match kind {
            LightType::Area => &["center", "u", "v", "samples", "jitter"],
            LightType::Point => &["position"],
            LightType::Environment => &["file", "rotation", "samples", "visible"],
            LightType::Directional => &["direction", "angle", "samples"],
            LightType::Spot => &["position", "direction", "inner_angle", "outer_angle"],
        }
    }

    fn describe(kind: LightType) -> &'static str {
        match kind {
            LightType::Area => "an area light",
            LightType::Point => "a point light",
            LightType::Environment => "an environment light",
            LightType::Directional => "a directional light",
            LightType::Spot => "a spot light",
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
            "file" => f.file = Some(map.next_value()?),
            "rotation" => f.rotation = Some(map.next_value()?),
            "visible" => f.visible = Some(map.next_value()?),
            "direction" => f.direction = Some(map.next_value()?),
            "angle" => f.angle = Some(map.next_value()?),
            "inner_angle" => f.inner_angle = Some(map.next_value()?),
            "outer_angle" => f.outer_angle = Some(map.next_value()?),
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
            LightType::Environment => LightDesc::Environment(EnvironmentLightDesc {
                file: f.file,
                color: f.color,
                intensity: f.intensity,
                rotation: f.rotation,
                samples: f.samples,
                visible: f.visible,
            }),
            LightType::Directional => LightDesc::Directional(DirectionalLightDesc {
                direction: f.direction.ok_or("direction")?,
                color: f.color,
                intensity: f.intensity,
                angle: f.angle,
                samples: f.samples,
            }),
            LightType::Spot => LightDesc::Spot(SpotLightDesc {
                position: f.position.ok_or("position")?,
                direction: f.direction.ok_or("direction")?,
                color: f.color,
                intensity: f.intensity,
                inner_angle: f.inner_angle,
                outer_angle: f.outer_angle,
            }),
        })
    }
}

impl<'de> Deserialize<'de> for LightDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        tagged::deserialize(d)
    }
}
