//! glTF 2.0 models (`.gltf` with external or data-URI buffers and images, and `.glb`): the
//! reader of the file's chosen scene into what the scene builder places. Parsing of the JSON
//! is the `gltf` crate's (with its validation of every index); penumbra resolves buffers and
//! images itself so that a missing `.bin` or image names the file and the JSON path, checks
//! every accessor and buffer view range before reading it, and never reads an image that no
//! used material needs.
//!
//! - **Scene graph:** the default scene, else scene 0 (else every root node, with a warning);
//!   node matrices and TRS, children (the graph must be a tree). Each node that uses a mesh is
//!   one [`MeshUse`]: the mesh (read once) and the node's matrix in the file's space.
//! - **Geometry:** one [`Mesh`] per glTF mesh, its primitives merged; primitive `k`'s
//!   triangles take the mesh's material slot of the primitive's material. Modes TRIANGLES,
//!   TRIANGLE_STRIP and TRIANGLE_FAN; POINTS and LINES are skipped with a warning. Indexed and
//!   not, u8/u16/u32 indices, byteStride, normalized integer attributes, sparse accessors.
//!   POSITION, NORMAL, the TEXCOORD_n the base-colour texture names (v flipped: glTF's v runs
//!   down the image, penumbra's t up) and COLOR_0.
//! - **Materials, cameras, lights:** see [`GltfMaterial`], [`GltfCamera`], [`GltfLight`].
//! - Everything else is ignored with a warning (animations, skins, morph targets, emissive,
//!   normal, occlusion and metallic-roughness maps, extensions penumbra does not read). A file that *requires* an extension penumbra
//!   does not read (Draco, meshopt, basisu, …) is refused, naming it.
//!
//! Every problem is a [`GltfError`] at a JSON path (`meshes[3].primitives[0].attributes.
//! POSITION`), never a panic: a truncated GLB, a wrong magic or version, a buffer or accessor
//! out of range, an index past the vertex count, a position that is not finite, a missing
//! `.bin`, a file without triangles. Memory follows the bytes: an accessor's size is checked
//! against its buffer view (and the memory budget) before anything is allocated.

mod accessor;
mod buffers;
mod container;
mod info;
mod json_path;
mod materials;
mod meshes;
mod nodes;

pub use info::{inspect_gltf, inspect_gltf_bytes, inspect_gltf_in, GltfInfo};
pub(crate) use nodes::unique;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_graph;

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Mat4, Vec2, Vec3, Vec4};

use crate::files::Files;
use crate::geometry::Mesh;
use crate::names::escape_controls;
use crate::texture::{Filter, Wrap};

/// Largest `.gltf`, `.glb` or `.bin` file read: as for OBJ files.
const MAX_FILE_BYTES: u64 = super::obj::MAX_FILE_BYTES;

/// A glTF file that cannot be read: where in its JSON (empty for the file as a whole) and
/// what is wrong. It does not name the file; the caller does.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GltfError {
    /// JSON path of the value at fault, as `meshes[0].primitives[1].indices`.
    pub at: String,
    /// What is wrong, one line.
    pub message: String,
}

impl GltfError {
    /// The error at `at`; control characters in either (from the file's own names and URIs)
    /// are written as escapes, so that the message stays one line.
    fn new(at: impl Into<String>, message: impl Into<String>) -> GltfError {
        GltfError {
            at: escape_controls(&at.into()),
            message: escape_controls(&message.into()),
        }
    }
}

impl fmt::Display for GltfError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self.at.is_empty() {
            true => f.write_str(&self.message),
            false => write!(f, "{}: {}", self.at, self.message),
        }
    }
}

impl std::error::Error for GltfError {}

type Result<T> = std::result::Result<T, GltfError>;

/// What a glTF file's chosen scene holds, in the file's own space (metres, +y up).
#[derive(Clone, Debug, Default)]
pub(crate) struct GltfModel {
    /// The meshes the scene uses, each read once; [`MeshUse::mesh`] indexes this.
    pub meshes: Vec<GltfMesh>,
    /// Every use of a mesh by a node, in scene order.
    pub uses: Vec<MeshUse>,
    /// Every material of the file, by its glTF index.
    pub materials: Vec<GltfMaterial>,
    /// Images by glTF index: `Some` for those a used material's texture needs.
    pub images: Vec<Option<ImageSource>>,
    /// Perspective cameras of the scene's nodes, in scene order, with unique names.
    pub cameras: Vec<GltfCamera>,
    /// Lights of the scene's nodes, in scene order.
    pub lights: Vec<GltfLight>,
    /// The file's `extensionsUsed`.
    pub extensions: Vec<String>,
    /// What was ignored, one sentence each.
    pub warnings: Vec<String>,
}

/// One glTF mesh: its primitives merged into one object-space mesh.
#[derive(Clone, Debug)]
pub(crate) struct GltfMesh {
    /// The triangles; `material_slots` index `materials`.
    pub mesh: Mesh,
    /// The glTF material of each slot (`None`: the default material).
    pub materials: Vec<Option<usize>>,
    /// The mesh's name in the file, or `meshes[i]`.
    pub name: String,
}

/// A node's use of a mesh.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MeshUse {
    /// Index into [`GltfModel::meshes`].
    pub mesh: usize,
    /// The node's world matrix in the file's space (its ancestors' matrices applied).
    pub matrix: Mat4,
}

/// How a material's alpha is read (`alphaMode`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum AlphaMode {
    /// Alpha ignored.
    Opaque,
    /// Cut out below the cutoff.
    Mask(f32),
    /// Blended; read as a cut-out at 0.5 (see `build::gltf::cutout_of`).
    Blend,
}

/// A glTF material, as penumbra reads it.
#[derive(Clone, Debug)]
pub(crate) struct GltfMaterial {
    /// Its name, or `materials[i]`.
    pub name: String,
    /// `baseColorFactor`, linear RGBA.
    pub base_color: Vec4,
    /// `baseColorTexture`, when its image is available.
    pub texture: Option<TextureRef>,
    /// `metallicFactor` in [0, 1].
    pub metallic: f32,
    /// `roughnessFactor` in [0, 1].
    pub roughness: f32,
    /// `alphaMode` and `alphaCutoff`.
    pub alpha: AlphaMode,
}

/// A base-colour texture: its image, sampler and uv transform (in penumbra's uv convention,
/// t up).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TextureRef {
    /// Index into [`GltfModel::images`].
    pub image: usize,
    /// The sampler's magnification filter.
    pub filter: Filter,
    /// The sampler's wrap mode (of s; t's when it differs is warned about).
    pub wrap: Wrap,
    /// uv → uv·scale + offset before lookup (KHR_texture_transform, flipped to t up).
    pub uv_scale: Vec2,
    /// See `uv_scale`.
    pub uv_offset: Vec2,
    /// Which TEXCOORD_n the texture reads.
    pub tex_coord: u32,
}

/// Where an image's bytes are.
#[derive(Clone, Debug)]
pub(crate) enum ImageSource {
    /// In a buffer view or a data URI, decoded.
    Bytes(Arc<[u8]>),
    /// In a file beside the glTF file.
    File(PathBuf),
}

/// A camera of a node, in the file's space: perspective, or orthographic.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct GltfCamera {
    /// The camera's name, else the node's, else `camera`; made unique in the file.
    pub name: String,
    /// The node's world matrix: the camera sits at its origin looking down −z, +y up.
    pub matrix: Mat4,
    /// `yfov` in degrees (a perspective camera's; 60 for an orthographic one, unused).
    pub fov_y_deg: f32,
    /// An orthographic camera's `ymag`: half the height it sees, in the node's units.
    pub ymag: Option<f32>,
}

impl GltfCamera {
    /// (position, look_at, up) after `world` (the placing object's transform).
    pub fn view(&self, world: Mat4) -> (Vec3, Vec3, Vec3) {
        let m = world * self.matrix;
        let position = m.transform_point3(Vec3::ZERO);
        let forward = m.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let up = m.transform_vector3(Vec3::Y).normalize_or_zero();
        (position, position + forward, up)
    }

    /// An orthographic camera's height of view after `world`: 2·ymag in its node's units,
    /// scaled with its up axis; `None` for a perspective camera.
    pub fn orthographic_height(&self, world: Mat4) -> Option<f32> {
        let scale = (world * self.matrix).transform_vector3(Vec3::Y).length();
        self.ymag.map(|ymag| 2.0 * ymag * scale)
    }
}

/// A light of a node (KHR_lights_punctual), in the file's space.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct GltfLight {
    /// Where it is (the node's origin).
    pub position: Vec3,
    /// Where it shines: the node's −z.
    pub direction: Vec3,
    /// Linear RGB colour.
    pub color: Vec3,
    /// Luminous intensity in candela (point, spot) or illuminance in lux (directional).
    pub intensity: f32,
    /// Its kind.
    pub kind: GltfLightKind,
}

/// The kinds of KHR_lights_punctual lights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum GltfLightKind {
    /// Emitting equally every way.
    Point,
    /// A cone about `direction`, with half-angles in radians.
    Spot {
        /// Full intensity inside.
        inner: f32,
        /// Nothing outside.
        outer: f32,
    },
    /// Parallel light travelling along `direction`.
    Directional,
}

/// Reads the glTF or GLB file at `path` through `files`. `max_bytes` bounds the memory its
/// geometry may take.
pub(crate) fn load_gltf(files: &Files, path: &Path, max_bytes: Option<u64>) -> Result<GltfModel> {
    let bytes = files
        .read(path, MAX_FILE_BYTES)
        .map_err(|e| GltfError::new("", e.to_string()))?;
    let dir = path.parent().map(Path::to_owned).unwrap_or_default();
    parse_gltf(&bytes, &dir, files, max_bytes)
}

/// Reads a glTF or GLB file's `bytes`; external buffers and images are relative to `dir`.
pub(crate) fn parse_gltf(
    bytes: &[u8],
    dir: &Path,
    files: &Files,
    max_bytes: Option<u64>,
) -> Result<GltfModel> {
    let parsed = container::parse(bytes)?;
    let mut reader = Reader {
        doc: &parsed.document,
        buffers: buffers::Buffers::new(parsed.blob, dir, files),
        budget: max_bytes,
        used: 0,
        ignored: Ignored::default(),
    };
    let mut model = GltfModel {
        extensions: parsed
            .document
            .extensions_used()
            .map(str::to_owned)
            .collect(),
        ..GltfModel::default()
    };
    reader.scene(&mut model)?;
    if model.meshes.iter().all(|m| m.mesh.is_empty()) {
        return Err(GltfError::new(
            "",
            "the file's scene has no triangles (no node uses a mesh with triangle primitives)",
        ));
    }
    model.warnings = reader.ignored.sentences();
    Ok(model)
}

/// The reader's state: the document, its buffers (read when first needed), the memory the
/// geometry may still take, and what was ignored.
struct Reader<'a> {
    doc: &'a gltf::Document,
    buffers: buffers::Buffers<'a>,
    budget: Option<u64>,
    used: u64,
    ignored: Ignored,
}

impl Reader<'_> {
    /// Counts `bytes` more of geometry, refusing them (at `at`) when over the budget.
    fn take(&mut self, at: &str, bytes: u64) -> Result<()> {
        let used = self.used.saturating_add(bytes);
        if let Some(budget) = self.budget.filter(|&b| used > b) {
            return Err(GltfError::new(
                at,
                format!(
                    "reading this takes the model to about {} of memory, more than the {} \
                     available",
                    crate::memory::human(used),
                    crate::memory::human(budget)
                ),
            ));
        }
        self.used = used;
        Ok(())
    }
}

/// What the reader ignored, counted by kind, for one warning per kind.
#[derive(Default)]
struct Ignored(BTreeMap<&'static str, usize>);

impl Ignored {
    /// Counts one more of `what` (a sentence with `{n}` where the count goes).
    fn note(&mut self, what: &'static str) {
        *self.0.entry(what).or_default() += 1;
    }

    /// Counts `n` more of `what`.
    fn add(&mut self, what: &'static str, n: usize) {
        if n > 0 {
            *self.0.entry(what).or_default() += n;
        }
    }

    fn sentences(&self) -> Vec<String> {
        self.0
            .iter()
            .map(|(what, n)| what.replace("{n}", &n.to_string()))
            .collect()
    }
}
