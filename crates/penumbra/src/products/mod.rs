//! The files a batch leaves beside its images, each written by one function that the command
//! line and Python (through `_core`) both call, so that the two write the same bytes:
//!
//! - [`record`]: the record beside an image (`out.png` → `out.meta.json`): how it was made
//!   ([`RecordSettings`], a named serialization, never Debug text), the files written with
//!   their digests, the camera and the object ids; and the rule that says a view is done;
//! - [`poses`]: every image's camera in penumbra's layout, NeRF's `transforms.json` or
//!   COLMAP's text model ([`colmap`]);
//! - [`manifest`]: one JSON line per task, appended;
//! - [`output_name`]: output patterns (`out/{camera}_{frame:04}.png`) and their checks;
//! - [`aov_files`]: the AOV files (a multi-layer EXR, PFM and id EXR files, Python's NPZ).
//!
//! Every file but the manifest is staged under a temporary name and renamed into place
//! ([`StagedFile`](crate::StagedFile)); errors name the file asked for.

pub mod aov_files;
pub mod colmap;
mod error;
mod frames;
pub mod manifest;
mod npz;
pub mod output_name;
pub mod poses;
pub mod record;
mod settings;

pub use error::ProductError;
pub use npz::{npz_bytes, NpyArray, NpyData};
pub use settings::{CameraRecord, RecordSettings, RenderRecord};
