//! penumbra: a fast, exact CPU ray tracer for direct lighting, soft shadows and textures.
//!
//! Data flows one way: a scene file is parsed into a [`SceneFile`] (its [`SceneDesc`] mirrors
//! the file) and built into a [`Scene`]: a shared [`World`] (geometry with its BVH,
//! materials, textures, lights, every camera by name) and the file's default
//! [`RenderSettings`]. [`render`] takes the world and settings per call, so one world renders
//! any camera, size, sampler or seed without a rebuild, into a [`Film`] of linear RGB that
//! [`write_image`] writes. A world can also be made from data with a [`WorldBuilder`].
//!
//! ```
//! use penumbra::{render, RenderOptions, RenderSettings, SceneFile, SceneFormat};
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
//! let scene = file.build(0)?;
//! let (film, _stats) = render(&scene.world, &scene.settings, &RenderOptions::default())?;
//! // Lit head-on, the default grey diffuse (0.8) reflects about 0.8.
//! assert!((film.get(4, 4).x - 0.8).abs() < 0.01);
//!
//! // Another size and sampler from the same world: nothing is rebuilt.
//! let quick = RenderSettings { width: 4, height: 4, spp: 1, ..scene.settings.clone() };
//! let (small, _) = render(&scene.world, &quick, &RenderOptions::default())?;
//! assert_eq!((small.width, small.height), (4, 4));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// `unsafe` is denied everywhere but `simd`, which dispatches the hot kernels to the
// instruction set the CPU has (each block with its SAFETY note).
#![deny(unsafe_code)]
#![warn(missing_docs)]

mod accel;
mod camera;
mod camera_path;
mod distribution;
mod encode8;
mod files;
mod film;
mod fnv;
mod geometry;
mod image_error;
mod image_format;
mod image_io;
mod integrator;
mod light;
mod material;
mod math;
mod memory;
mod names;
mod pool;
mod pose;
pub mod products;
mod raycast;
mod reach;
mod render;
mod sampling;
mod scale;
mod scene;
mod simd;
mod staged;
mod texture;
mod texture_file;
mod world;

/// The built-in shapes as object-space meshes, for [`WorldBuilder::add_mesh`].
pub mod shapes {
    pub use crate::geometry::{cube, quad, sphere, triangle, SPHERE_RINGS, SPHERE_SEGMENTS};
}

/// Hooks for the benchmarks and the integration tests: the two-level structure a [`World`]
/// traverses ([`World::accel`]), the shadow queries it answers on a forced SIMD path (the `_on`
/// methods), and the brute-force references. Not a stable API: it follows the engine's shape.
#[doc(hidden)]
pub mod bench {
    pub use crate::accel::{intersect_brute_force, occluded_brute_force, Levels, Pairs, Segments};
}

pub use accel::prim::moller_trumbore::intersect_triangle;
pub use accel::Bvh;
pub use camera::{
    Aperture, Camera, CameraError, DistortionError, FilmCamera, FisheyeDistortion, Lens,
    OpenCvDistortion, Optics, FRAMING_CAMERA, FRAMING_FOV_DEG,
};
pub use camera_path::{CameraKey, CameraPath, Orbit, PathError, MAX_PATH_FRAMES};
pub use encode8::{encode_8bit, film_codes};
pub use files::Files;
pub use film::Film;
pub use fnv::FileDigest;
pub use geometry::{Geometry, Hit, Mesh, Surface, Triangle, TriangleHit};
pub use image_error::ImageError;
pub use image_format::OutputFormat;
pub use image_io::{check_finite, encode_image, stage_image, write_image, write_image_unless};
pub use integrator::{LightModel, Shading};
pub use light::{
    AreaLight, DirectionalLight, EnvironmentError, EnvironmentLight, EnvironmentMap,
    EnvironmentSample, Light, PointLight, SpotLight,
};
pub use material::{Cutout, Material};
pub use math::{Aabb, Ray, Rgb, Transform};
pub use names::{escape_controls, file_name_part, UnknownName};
pub use pool::MAX_THREADS;
pub use pose::{CameraPose, Mat3Rows, Mat4Rows};
pub use raycast::{
    create_rays_pinhole, create_rays_pinhole_fov, CastRays, ClosestPoints, Intersections,
    QueryOptions, RaycastError, RaycastingScene, INVALID_ID,
};
pub use reach::{Outside, RULE};
pub use render::{
    render, render_with_aovs, Aov, AovFilm, AovPixel, AovValues, Pass, PassSink, PixelBounds,
    RenderError, RenderOptions, RenderSettings, RenderStats, SettingsError, SettingsPatch, Tile,
    TileSink, View, MAX_LIGHT_SAMPLES, MAX_PIXELS, MAX_SPP, NO_ID,
};
pub use sampling::{Rng, Sampler};
pub use scale::{MAX_COORDINATE, MAX_REACH, MIN_EXTENT};
pub use scene::{
    camera_from_table, desc, inspect_gltf, inspect_gltf_bytes, inspect_gltf_in, inspect_mtl,
    inspect_obj, inspect_obj_bytes, inspect_obj_in, inspect_ply, inspect_ply_bytes, AssetKind,
    ErrorKind, GltfInfo, Location, ModelFormat, ObjInfo, Override, OverrideError, PackError, Scene,
    SceneDesc, SceneError, SceneFile, SceneFormat, ScenePack, MAX_SCENE_BYTES,
};
pub use simd::{forced_simd_path, simd_path, supported_paths, SimdEnvError, SimdPath};
pub use staged::{commit_all, leftovers, staged_for, StagedFile};
pub use texture::{Filter, Image, ImageTexture, Texture, TextureKind, Wrap};
pub use texture_file::decode_texture_image;
pub use world::{
    flatten_instances, ObjectIndex, SurfaceAttributes, World, WorldBuilder, WorldError, WorldStats,
    DEFAULT_MATERIAL, FLATTEN_TRIANGLES, MAX_INSTANCES, MAX_TRIANGLES,
};

// The README's Rust snippets are compiled (and, unless `no_run`, run) as doc-tests.
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
struct ReadmeDoctests;
