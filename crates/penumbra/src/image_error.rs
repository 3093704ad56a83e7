//! Why an image could not be written or read: the one error type of image files, shared by
//! the encoders (`image_io`) and the staged writes (`staged`).

use std::path::PathBuf;

use thiserror::Error;

use crate::memory::human;

/// Why an image could not be written or read.
#[derive(Debug, Error)]
pub enum ImageError {
    /// The extension is not one of .png, .jpg, .jpeg, .exr, .pfm.
    #[error("{}: unknown image format (use .png, .jpg, .exr or .pfm)", path.display())]
    UnknownFormat {
        /// The path.
        path: PathBuf,
    },
    /// Encoding in memory failed.
    #[error("cannot encode image: {message}")]
    Encode {
        /// The cause.
        message: String,
    },
    /// Writing failed.
    #[error("{}: cannot write image: {message}", path.display())]
    Write {
        /// The path.
        path: PathBuf,
        /// The cause.
        message: String,
    },
    /// A float image (EXR, PFM) would hold an infinite or NaN value: radiance beyond the f32
    /// range, such as the physical light model's inverse-square falloff right next to a
    /// very bright light. Nothing is written.
    #[error("{}: pixel ({x}, {y}) is {value}, beyond the range of 32-bit floats: the scene's lights or materials are too bright", path.display())]
    NonFinite {
        /// The path.
        path: PathBuf,
        /// Column of the first such pixel.
        x: u32,
        /// Row of the first such pixel, from the top.
        y: u32,
        /// Its first non-finite channel.
        value: f32,
    },
    /// A film with alpha for a format without an alpha channel (JPEG, PFM).
    #[error("{}: {format} has no alpha channel; write the alpha to .png or .exr", path.display())]
    NoAlpha {
        /// The path, or "standard output".
        path: PathBuf,
        /// The format's name.
        format: &'static str,
    },
    /// The gamma of an 8-bit encoding is not a positive number with a finite inverse.
    #[error("gamma must be a positive finite number, not {0}")]
    BadGamma(f32),
    /// The image is wider or higher than its format can store (JPEG: 65535 pixels a side).
    #[error("{}: a {width}x{height} image is too large for {format}, which stores at most {limit} pixels a side", path.display())]
    TooLarge {
        /// The path, or "standard output".
        path: PathBuf,
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// The format's name.
        format: &'static str,
        /// The format's largest width and height.
        limit: u32,
    },
    /// Encoding the image would take more memory than the process may still take. Nothing
    /// is written.
    #[error("{}: not enough memory to encode a {width}x{height} {format}: it needs about {}, more than the {} available", path.display(), human(*need), human(*available))]
    OutOfMemory {
        /// The path, or "standard output".
        path: PathBuf,
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// The format's name.
        format: &'static str,
        /// Bytes the encoding needs beyond the film.
        need: u64,
        /// Bytes available.
        available: u64,
    },
    /// The cancel flag was set before the image was complete; the file is as it was.
    #[error("interrupted")]
    Cancelled,
}

impl ImageError {
    /// `Ok` for the gamma of an 8-bit encoding: `None` (the sRGB curve) or a positive finite
    /// number whose inverse is finite too; [`ImageError::BadGamma`] for 0, a negative, NaN or
    /// infinite value. Writing images checks it; callers that encode 8-bit values themselves
    /// call it first.
    pub fn check_gamma(gamma: Option<f32>) -> Result<(), ImageError> {
        match gamma {
            Some(g) if !(g > 0.0 && g.is_finite() && (1.0 / g).is_finite()) => {
                Err(ImageError::BadGamma(g))
            }
            _ => Ok(()),
        }
    }
}
