//! The image formats a film is written in, named by a file's extension or by the name users
//! type (`--format`, Python): `png`, `jpg` (or `jpeg`), `exr`, `pfm`.
//!
//! ```
//! use std::path::Path;
//! use penumbra::OutputFormat;
//!
//! assert_eq!("jpeg".parse(), Ok(OutputFormat::Jpeg));
//! assert_eq!(OutputFormat::Jpeg.extension(), "jpg");
//! assert_eq!(OutputFormat::from_path(Path::new("shot.EXR")), Some(OutputFormat::Exr));
//! ```

use std::path::Path;
use std::str::FromStr;

use crate::names::{parse_name, UnknownName};

/// Output file formats, chosen by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// 8-bit sRGB (or gamma-encoded) PNG.
    Png,
    /// 8-bit sRGB (or gamma-encoded) JPEG.
    Jpeg,
    /// Linear float OpenEXR.
    Exr,
    /// Linear float Portable Float Map.
    Pfm,
}

impl OutputFormat {
    /// Every format, in the order messages list them.
    pub const ALL: [OutputFormat; 4] = [
        OutputFormat::Png,
        OutputFormat::Jpeg,
        OutputFormat::Exr,
        OutputFormat::Pfm,
    ];

    /// The largest width and height the format can store (JPEG: 65535), or `None` when only
    /// memory limits it.
    pub fn max_dimension(self) -> Option<u32> {
        match self {
            OutputFormat::Jpeg => Some(u16::MAX as u32),
            OutputFormat::Png | OutputFormat::Exr | OutputFormat::Pfm => None,
        }
    }

    /// Whether it stores an alpha channel: PNG (straight alpha) and EXR (premultiplied, as
    /// OpenEXR says) do; JPEG and PFM do not.
    pub fn has_alpha(self) -> bool {
        matches!(self, OutputFormat::Png | OutputFormat::Exr)
    }

    /// Its name in messages: "PNG", "JPEG", "EXR" or "PFM".
    pub fn name(self) -> &'static str {
        match self {
            OutputFormat::Png => "PNG",
            OutputFormat::Jpeg => "JPEG",
            OutputFormat::Exr => "EXR",
            OutputFormat::Pfm => "PFM",
        }
    }

    /// The name users type and its usual extension: "png", "jpg", "exr" or "pfm";
    /// [`str::parse`] takes it back (and "jpeg" too).
    pub fn extension(self) -> &'static str {
        match self {
            OutputFormat::Png => "png",
            OutputFormat::Jpeg => "jpg",
            OutputFormat::Exr => "exr",
            OutputFormat::Pfm => "pfm",
        }
    }

    /// Memory that writing one pixel takes beyond the film, at most: the 8-bit codes (PNG,
    /// JPEG) and the compressed copy PNG's encoder keeps whole until it writes, or the float
    /// copy EXR's encoder reads; plus the encoded bytes when they are kept `in_memory`.
    pub(crate) fn bytes_per_pixel(self, in_memory: bool) -> u64 {
        let working = match self {
            OutputFormat::Png => 3 + 4,
            OutputFormat::Jpeg => 3,
            OutputFormat::Exr => 12,
            OutputFormat::Pfm => 0,
        };
        let encoded = match self {
            OutputFormat::Png | OutputFormat::Jpeg => 4,
            OutputFormat::Exr | OutputFormat::Pfm => 13,
        };
        working + if in_memory { encoded } else { 0 }
    }

    /// The format named by `path`'s extension (case-insensitive).
    pub fn from_path(path: &Path) -> Option<OutputFormat> {
        path.extension()?
            .to_str()?
            .to_ascii_lowercase()
            .parse()
            .ok()
    }
}

/// A format by its [`OutputFormat::extension`] or "jpeg", in lower case; an unknown name is an
/// error listing the names.
impl FromStr for OutputFormat {
    type Err = UnknownName;

    fn from_str(name: &str) -> Result<OutputFormat, UnknownName> {
        let name = if name == "jpeg" { "jpg" } else { name };
        parse_name(
            "image format",
            name,
            &OutputFormat::ALL,
            OutputFormat::extension,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_formats_by_extension() {
        let by_path = |p: &str| OutputFormat::from_path(Path::new(p));
        assert_eq!(by_path("a.PNG"), Some(OutputFormat::Png));
        assert_eq!(by_path("a.jpeg"), Some(OutputFormat::Jpeg));
        assert_eq!(by_path("a.JPG"), Some(OutputFormat::Jpeg));
        assert_eq!(by_path("a.exr"), Some(OutputFormat::Exr));
        assert_eq!(by_path("a.pfm"), Some(OutputFormat::Pfm));
        assert_eq!(by_path("a.bmp"), None);
        assert_eq!(by_path("a"), None);
    }

    #[test]
    fn format_names_round_trip() {
        for f in OutputFormat::ALL {
            assert_eq!(f.extension().parse::<OutputFormat>(), Ok(f));
            assert_eq!(
                OutputFormat::from_path(Path::new(&format!("a.{}", f.extension()))),
                Some(f)
            );
        }
        assert_eq!("jpeg".parse::<OutputFormat>(), Ok(OutputFormat::Jpeg));
        let e = "bmp".parse::<OutputFormat>().unwrap_err();
        assert_eq!(
            e.to_string(),
            r#"unknown image format "bmp" (use "png", "jpg", "exr" or "pfm")"#
        );
        // The typed name is exact: the case-folding is the extension's.
        assert!("PNG".parse::<OutputFormat>().is_err());
    }
}
