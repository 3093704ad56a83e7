//! penumbra: a fast, exact CPU ray tracer for direct lighting, soft shadows and textures.
//!
//! Data flows one way: a scene file is parsed into a [`SceneFile`] (its [`SceneDesc`] mirrors
//! the file), built into a [`Scene`] (world-space triangles, BVH, materials, lights, camera),
//! rendered into a [`Film`] of linear RGB, and written with [`write_image`].
//!
//! ```
//! use penumbra::{render, Overrides, RenderOptions, SceneFile, SceneFormat};
//!
//! let file = SceneFile::from_str(r#"
//!     [film]
//!     width = 8
//!     height = 8
//!     [camera]
//!     position = [0, 0, 3]
//!     look_at = [0, 0, 0]
//!     fov = 40
//!     [render]
//!     ambient = 0
//!     [[lights]]
//!     type = "point"
//!     position = [0, 0, 3]
//!     [[objects]]
//!     type = "quad"
//!     corner = [-1, -1, 0]
//!     u = [2, 0, 0]
//!     v = [0, 2, 0]
//! "#, SceneFormat::Toml, "doc.toml", ".")?;
//! let scene = file.build(&Overrides::default())?;
//! let (film, _stats) = render(&scene, &RenderOptions::default())?;
//! // Lit head-on, the default grey diffuse (0.8) reflects about 0.8.
//! assert!((film.get(4, 4).x - 0.8).abs() < 0.01);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod accel;
pub mod camera;
pub mod film;
pub mod geometry;
pub mod image_io;
pub mod integrator;
pub mod light;
pub mod material;
pub mod math;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod texture;

pub use film::Film;
pub use image_io::{write_image, ImageError, OutputFormat};
pub use render::{render, PixelBounds, RenderError, RenderOptions, RenderStats};
pub use sampling::Sampler;
pub use scene::{Overrides, Scene, SceneDesc, SceneError, SceneFile, SceneFormat};
