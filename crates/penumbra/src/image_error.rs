//! Why an image could not be written or read: the one error type of image files, shared by
//! the encoders (`image_io`) and the staged writes (`staged`).

use std::path::PathBuf;

use thiserror::Error;

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
    /// The cancel flag was set before the image was complete; the file is as it was.
    #[error("interrupted")]
    Cancelled,
}
