//! `[textures.NAME]`: one struct per kind, chosen by the table's `type` key (read by
//! `tagged`).

use serde::de::{Deserializer, MapAccess};
use serde::Deserialize;

use super::tagged::{self, Tagged};
use super::values::{ColorDesc, Num, Vec2Desc};
use crate::texture::{Filter, Wrap};

/// `[textures.NAME]`: where the colors come from, and the uv mapping `uv·uv_scale + uv_offset`.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureDesc {
    /// The texture's kind and its own keys.
    pub kind: TextureKindDesc,
    /// Default [1, 1].
    pub uv_scale: Option<Vec2Desc>,
    /// Default [0, 0].
    pub uv_offset: Option<Vec2Desc>,
}

/// A texture's kind, by its `type`.
#[derive(Clone, Debug, PartialEq)]
pub enum TextureKindDesc {
    /// `type = "image"`.
    Image(ImageTextureDesc),
    /// `type = "checker"`.
    Checker(CheckerTextureDesc),
}

/// An image file as a texture.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageTextureDesc {
    /// The image, relative to the scene file's folder.
    pub file: String,
    /// Default bilinear.
    pub filter: Option<Filter>,
    /// Default repeat.
    pub wrap: Option<Wrap>,
    /// Default sRGB.
    pub colorspace: Option<ColorSpace>,
}

/// The procedural checkerboard.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckerTextureDesc {
    /// Color where the square index sum is even (default 1).
    pub even: Option<ColorDesc>,
    /// Color elsewhere (default 0).
    pub odd: Option<ColorDesc>,
    /// Squares per unit of uv (default 8).
    pub checks: Option<Num>,
}

/// How an image's 8- or 16-bit values are decoded.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum ColorSpace {
    /// The sRGB curve (color images).
    Srgb,
    /// Values as they are (data such as masks).
    Linear,
}

/// The `type` of a texture.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum TextureType {
    /// An image file.
    Image,
    /// The procedural checkerboard.
    Checker,
}

#[derive(Default)]
pub(super) struct TextureFields {
    uv_scale: Option<Vec2Desc>,
    uv_offset: Option<Vec2Desc>,
    file: Option<String>,
    filter: Option<Filter>,
    wrap: Option<Wrap>,
    colorspace: Option<ColorSpace>,
    even: Option<ColorDesc>,
    odd: Option<ColorDesc>,
    checks: Option<Num>,
}

impl Tagged for TextureDesc {
    type Kind = TextureType;
    type Fields = TextureFields;
    const COMMON: &'static [&'static str] = &["uv_scale", "uv_offset"];
    const ALL: &'static [&'static str] = &[
        "file",
        "filter",
        "wrap",
        "colorspace",
        "even",
        "odd",
        "checks",
    ];

    const KINDS: &'static [TextureType] = &[TextureType::Image, TextureType::Checker];

    fn keys(kind: TextureType) -> &'static [&'static str] {
        match kind {
            TextureType::Image => &["file", "filter", "wrap", "colorspace"],
            TextureType::Checker => &["even", "odd", "checks"],
        }
    }

    fn describe(kind: TextureType) -> &'static str {
        match kind {
            TextureType::Image => "an image texture",
            TextureType::Checker => "a checker texture",
        }
    }

    fn read<'de, A: MapAccess<'de>>(
        f: &mut TextureFields,
        key: &str,
        map: &mut A,
    ) -> Result<(), A::Error> {
        match key {
            "uv_scale" => f.uv_scale = Some(map.next_value()?),
            "uv_offset" => f.uv_offset = Some(map.next_value()?),
            "file" => f.file = Some(map.next_value()?),
            "filter" => f.filter = Some(map.next_value()?),
            "wrap" => f.wrap = Some(map.next_value()?),
            "colorspace" => f.colorspace = Some(map.next_value()?),
            "even" => f.even = Some(map.next_value()?),
            "odd" => f.odd = Some(map.next_value()?),
            _ => f.checks = Some(map.next_value()?),
        }
        Ok(())
    }

    fn finish(kind: TextureType, f: TextureFields) -> Result<Self, &'static str> {
        let kind = match kind {
            TextureType::Image => TextureKindDesc::Image(ImageTextureDesc {
                file: f.file.ok_or("file")?,
                filter: f.filter,
                wrap: f.wrap,
                colorspace: f.colorspace,
            }),
            TextureType::Checker => TextureKindDesc::Checker(CheckerTextureDesc {
                even: f.even,
                odd: f.odd,
                checks: f.checks,
            }),
        };
        Ok(TextureDesc {
            kind,
            uv_scale: f.uv_scale,
            uv_offset: f.uv_offset,
        })
    }
}

impl<'de> Deserialize<'de> for TextureDesc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        tagged::deserialize(d)
    }
}
