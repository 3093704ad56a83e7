//! PLY vertex colours to linear RGB. A channel is scaled to [0, 1] by its type (integers by
//! their largest value, so `uchar` by 255; floats as they are), clamped to [0, 1], and read as
//! an sRGB-encoded display value, as Blender's PLY importer reads them by default (and
//! three.js, MeshLab and Open3D show them): decoded to linear with the sRGB curve.

use super::header::Scalar;
use super::roles::color_range;
use crate::texture::srgb_to_linear;

/// Decodes colour channels; holds the 256 `uchar` values decoded once per file.
pub(super) struct Decoder {
    bytes: [f32; 256],
}

impl Decoder {
    /// A decoder with its `uchar` table filled.
    pub(super) fn new() -> Decoder {
        let mut bytes = [0.0; 256];
        for (i, b) in bytes.iter_mut().enumerate() {
            *b = decode(i as f64, Scalar::U8);
        }
        Decoder { bytes }
    }

    /// The linear value of the finite channel value `value` of type `ty`.
    #[inline]
    pub(super) fn decode(&self, value: f64, ty: Scalar) -> f32 {
        match ty {
            // A uchar value is a whole number in 0..=255.
            Scalar::U8 => self.bytes[value as u8 as usize],
            _ => decode(value, ty),
        }
    }
}

/// The linear value of the channel value `value` of type `ty`.
fn decode(value: f64, ty: Scalar) -> f32 {
    srgb_to_linear((value / color_range(ty)).clamp(0.0, 1.0) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channels_scale_by_their_type_then_decode_from_srgb() {
        let d = Decoder::new();
        assert_eq!(d.decode(255.0, Scalar::U8), 1.0);
        assert_eq!(d.decode(0.0, Scalar::U8), 0.0);
        assert_eq!(d.decode(65535.0, Scalar::U16), 1.0);
        assert_eq!(d.decode(1.0, Scalar::F32), 1.0);
        // sRGB 0.5 is about 0.214 linear, whether written as a byte or a float.
        assert!((d.decode(0.5, Scalar::F32) - 0.2140).abs() < 1e-4);
        assert!((d.decode(128.0, Scalar::U8) - 0.2158).abs() < 1e-4);
        assert_eq!(d.decode(128.0, Scalar::U8), decode(128.0, Scalar::U8));
        // Out of range: clamped.
        assert_eq!(d.decode(3.0, Scalar::F64), 1.0);
        assert_eq!(d.decode(-1.0, Scalar::I8), 0.0);
    }
}
