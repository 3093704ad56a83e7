//! A model is a scene: a bare mesh file (`.obj`, `.ply`, `.gltf` or `.glb`) becomes the scene
//! description a TOML file would give, with one `type = "mesh"` object naming it, a camera
//! that frames its bounds and a default light rig. Overrides, packs and building then work on
//! it unchanged. A glTF file with cameras uses them instead (`cameras = true`: the first is
//! the view), and one with lights uses them instead of the rig (`lights = true`, under
//! the physical light model, whose 1/d² falloff is glTF's).
//!
//! The defaults, from the mesh's bounds (centre c, bounding-sphere radius r = half the
//! diagonal):
//! - camera: fov 40°, up +y, looking at c from c + d·normalize(1, 0.8, 1.4) (front-right-above)
//!   with d = r / sin(20°) ≈ 2.92·r, the distance at which the bounding sphere fits the
//!   vertical field of view;
//! - light: one area light, a horizontal square of side 2r/3 (a third of the diagonal) facing
//!   down, centred at c + 3r·normalize(−1, 2, 1) (above front-left), 4×4 samples, intensity 1
//!   (under the default Phong model a white diffuse surface facing it is lit to about 1), plus
//!   `render.ambient` 0.1;
//! - film 800×600, sampler `rgss` with 4 samples per pixel.
//!
//! ```
//! use penumbra::SceneFile;
//!
//! let dir = std::env::temp_dir().join(format!("penumbra-model-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//! let obj = dir.join("tri.obj");
//! std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")?;
//! let file = SceneFile::load(&obj)?;
//! assert_eq!(file.desc.objects.len(), 1);
//! assert_eq!(file.build(1)?.settings.width, 800);
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::{Path, PathBuf};

use glam::DVec3;

use super::error::{AssetKind, ErrorKind, Location};
use super::obj::obj_bounds;
use super::parse::Source;
use super::ply::ply_bounds;
use super::{inspect_gltf_in, Override, SceneError, SceneFile, SceneFormat};
use crate::camera::{framing_view, FRAMING_FOV_DEG};
use crate::files::Files;
use crate::math::Aabb;

/// Direction from the bounds' centre to the default area light (normalized before use).
const MODEL_LIGHT_DIR: [f64; 3] = [-1.0, 2.0, 1.0];

/// The kinds of mesh file a model can be.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelFormat {
    /// Wavefront OBJ (with its MTL materials).
    Obj,
    /// PLY (no materials: the default one).
    Ply,
    /// glTF 2.0, as JSON (`.gltf`) or binary (`.glb`).
    Gltf,
}

impl ModelFormat {
    /// The format a file name's extension (in any case) names, if it is a mesh file.
    pub fn from_path(path: &Path) -> Option<ModelFormat> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "obj" => Some(ModelFormat::Obj),
            "ply" => Some(ModelFormat::Ply),
            "gltf" | "glb" => Some(ModelFormat::Gltf),
            _ => None,
        }
    }
}

impl SceneFile {
    /// The scene of a bare mesh file (`.obj` or `.ply`): the mesh, a camera framing its
    /// bounds and the default light rig (see the module `model`'s docs). The mesh is read
    /// once here for its bounds, and again when the scene is built. Its
    /// [`text`](SceneFile::text) is the TOML scene written for it; errors about that scene
    /// name the key (and any override), never a line, since the user never saw the text.
    pub fn for_model(path: impl AsRef<Path>) -> Result<SceneFile, SceneError> {
        SceneFile::for_model_with(path, &[])
    }

    /// [`SceneFile::for_model`] with `overrides` applied in order (see [`Override`]), as
    /// to the keys of a scene file.
    pub fn for_model_with(
        path: impl AsRef<Path>,
        overrides: &[Override],
    ) -> Result<SceneFile, SceneError> {
        SceneFile::for_model_in(path.as_ref(), overrides, Files::disk())
    }

    /// [`SceneFile::for_model_with`] reading the model's files through `files`.
    pub(super) fn for_model_in(
        path: &Path,
        overrides: &[Override],
        files: Files,
    ) -> Result<SceneFile, SceneError> {
        let format = ModelFormat::from_path(path).ok_or_else(|| SceneError::UnknownFormat {
            path: path.to_owned(),
        })?;
        std::fs::metadata(path).map_err(|source| SceneError::Read {
            path: path.to_owned(),
            source,
        })?;
        let (bounds, imports) = match format {
            ModelFormat::Obj => (obj_bounds(&files, path), Imports::default()),
            ModelFormat::Ply => (ply_bounds(path), Imports::default()),
            ModelFormat::Gltf => match inspect_gltf_in(&files, path) {
                Ok(i) => {
                    let imports = Imports {
                        cameras: !i.cameras.is_empty(),
                        lights: i.lights > 0,
                    };
                    (Ok(i.bounds), imports)
                }
                Err(e) => (Err(e), Imports::default()),
            },
        };
        let bounds = bounds.map_err(|message| mesh_error(path, message))?;
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .ok_or_else(|| mesh_error(path, "the file name is not UTF-8 text".into()))?;
        let text = model_scene_text(name, bounds, imports);
        let base_dir = path.parent().map(Path::to_owned).unwrap_or_default();
        let source = Source::new(path.to_owned(), text, SceneFormat::Toml).generated();
        Ok(SceneFile::from_source(source, base_dir, overrides)?.with_files(files))
    }
}

/// What a model file brings of its own instead of the defaults.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Imports {
    /// Its cameras: no default camera.
    pub cameras: bool,
    /// Its lights: no default rig, the physical light model.
    pub lights: bool,
}

/// An error about the mesh file itself, naming it.
fn mesh_error(path: &Path, message: String) -> SceneError {
    SceneError::Invalid {
        kind: ErrorKind::Asset(AssetKind::Mesh),
        location: Box::new(Location {
            file: PathBuf::from(path),
            line: None,
            column: None,
            key: None,
            set_by: None,
        }),
        message,
    }
}

/// The default area light for `bounds`: (center, side). The square is horizontal (u along
/// +x, v along +z, so it faces −y), of side 2r/3, at 3r from the centre toward
/// [`MODEL_LIGHT_DIR`].
pub(crate) fn model_light(bounds: Aabb) -> (DVec3, f64) {
    let (centre, radius) = bounds.bounding_sphere().unwrap_or((DVec3::ZERO, 1.0));
    let dir = DVec3::from(MODEL_LIGHT_DIR).normalize();
    (centre + 3.0 * radius * dir, 2.0 * radius / 3.0)
}

/// The TOML text of the scene of the mesh file `file_name` (relative to the scene's folder)
/// whose bounds are `bounds`, with the file's own cameras and lights when `imports` says so.
pub(crate) fn model_scene_text(file_name: &str, bounds: Aabb, imports: Imports) -> String {
    let (position, look_at) = framing_view(bounds);
    let (light, side) = model_light(bounds);
    let file = toml::Value::String(file_name.to_owned());
    let camera = match imports.cameras {
        true => String::new(),
        false => format!(
            "[camera]\nposition = {}\nlook_at = {}\nup = [0.0, 1.0, 0.0]\nfov = {FRAMING_FOV_DEG:?}\n\n",
            vector(position),
            vector(look_at),
        ),
    };
    let lights = match imports.lights {
        true => String::new(),
        false => format!(
            "[[lights]]\ntype = \"area\"\ncenter = {}\nu = [{side:?}, 0.0, 0.0]\n\
             v = [0.0, 0.0, {side:?}]\nsamples = 4\nintensity = 1.0\n\n",
            vector(light),
        ),
    };
    let model = match imports.lights {
        true => "light_model = \"physical\"\n",
        false => "",
    };
    let mut object = format!("[[objects]]\ntype = \"mesh\"\nfile = {file}\n");
    if imports.cameras {
        object.push_str("cameras = true\n");
    }
    if imports.lights {
        object.push_str("lights = true\n");
    }
    format!(
        "# The scene of a bare model file: a camera framing its bounds (or the file's cameras)\n\
         # and the default light rig (or the file's lights).\n\
         [film]\nwidth = 800\nheight = 600\n\n\
         {camera}\
         [render]\nsampler = \"rgss\"\nsamples = 4\nambient = 0.1\n{model}\n\
         {lights}\
         {object}"
    )
}

/// A TOML array of three floats (`{:?}` writes a float TOML reads back exactly: `1.0`,
/// `1e20`).
fn vector(v: DVec3) -> String {
    format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn unit_box() -> Aabb {
        Aabb::EMPTY
            .grow(Vec3::new(-1.0, -1.0, -1.0))
            .grow(Vec3::new(1.0, 1.0, 1.0))
    }

    #[test]
    fn the_camera_sees_the_bounding_sphere_exactly_fill_the_vertical_fov() {
        let (position, look_at) = framing_view(unit_box());
        assert_eq!(look_at, DVec3::ZERO);
        let r = 3f64.sqrt();
        // The sphere's silhouette half-angle asin(r/d) is half the fov.
        let half = (r / position.length()).asin().to_degrees();
        assert!((half - 20.0).abs() < 1e-9, "{half}");
        let dir = position.normalize();
        assert!(
            dir.x > 0.0 && dir.y > 0.0 && dir.z > 0.0,
            "front-right-above: {dir}"
        );
    }

    #[test]
    fn the_light_is_above_front_left_and_a_third_of_the_diagonal() {
        let (center, side) = model_light(unit_box());
        assert!(
            center.x < 0.0 && center.y > 0.0 && center.z > 0.0,
            "{center}"
        );
        assert!((side - 2.0 * 3f64.sqrt() / 3.0).abs() < 1e-12);
    }

    #[test]
    fn a_point_is_framed_as_a_unit_sphere() {
        let point = Aabb::EMPTY.grow(Vec3::new(2.0, 0.0, 0.0));
        let (position, look_at) = framing_view(point);
        assert_eq!(look_at, DVec3::new(2.0, 0.0, 0.0));
        let d = (position - look_at).length();
        assert!((d - 1.0 / 20f64.to_radians().sin()).abs() < 1e-9);
    }

    #[test]
    fn the_text_parses_with_the_file_name_quoted() {
        let text = model_scene_text("a \"b\".obj", unit_box(), Imports::default());
        let file = SceneFile::from_str(&text, SceneFormat::Toml, "x.obj", ".").unwrap();
        assert_eq!(file.desc.objects.len(), 1);
        assert_eq!(file.desc.lights.len(), 1);
        let value: toml::Value = toml::from_str(&text).unwrap();
        assert_eq!(value["objects"][0]["file"].as_str(), Some("a \"b\".obj"));
    }

    #[test]
    fn huge_bounds_give_floats_toml_reads() {
        let huge = Aabb::EMPTY.grow(Vec3::splat(-1e30)).grow(Vec3::splat(1e30));
        let text = model_scene_text("m.ply", huge, Imports::default());
        SceneFile::from_str(&text, SceneFormat::Toml, "m.ply", ".").unwrap();
    }

    #[test]
    fn other_extensions_are_not_models() {
        assert_eq!(
            ModelFormat::from_path(Path::new("a.OBJ")),
            Some(ModelFormat::Obj)
        );
        assert_eq!(
            ModelFormat::from_path(Path::new("a.ply")),
            Some(ModelFormat::Ply)
        );
        assert_eq!(
            ModelFormat::from_path(Path::new("a.GLB")),
            Some(ModelFormat::Gltf)
        );
        assert_eq!(ModelFormat::from_path(Path::new("a.fbx")), None);
        assert!(matches!(
            SceneFile::for_model("a.toml"),
            Err(SceneError::UnknownFormat { .. })
        ));
    }

    #[test]
    fn errors_in_the_written_scene_name_the_key_not_a_line() {
        let dir = std::env::temp_dir().join(format!("penumbra-model-key-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let obj = dir.join("tri.obj");
        std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let file = SceneFile::for_model(&obj).unwrap();
        let path = super::super::KeyPath::root("camera").key("position");
        let err = file.error(ErrorKind::BadValue, &path, "too far");
        std::fs::remove_dir_all(&dir).unwrap();
        let location = err.location().unwrap();
        assert_eq!((location.line, location.column), (None, None));
        assert_eq!(location.key.as_deref(), Some("camera.position"));
        assert_eq!(location.file, obj);
    }

    #[test]
    fn a_missing_file_is_a_read_error_naming_it() {
        let err = SceneFile::for_model("no/such/model.obj").unwrap_err();
        assert!(matches!(err, SceneError::Read { .. }));
        assert!(err.to_string().starts_with("no/such/model.obj: "), "{err}");
    }
}
