//! Where copies of a mesh go: the placements of `type = "instances"` (an inline list or a
//! `.npy` file of matrices), and how many copies of each OBJ file the scene places, which
//! decides whether the file is copied per use or built once and instanced
//! ([`flatten_instances`](crate::world::flatten_instances)).

use std::collections::HashMap;
use std::path::PathBuf;
use std::rc::Rc;

use glam::{Mat4, Vec3};

use super::budget::BYTES_PER_INSTANCE;
use super::{Builder, Result};
use crate::math::srt_matrix;
use crate::math::Transform;
use crate::scale::Problem;
use crate::scene::desc::{
    ColorDesc, Matrix, ObjectDesc, PlacementDesc, ShapeDesc, TransformsDesc, Vec3Desc,
};
use crate::scene::error::{AssetKind, ErrorKind, KeyPath};
use crate::scene::npy;
use crate::scene::{SceneError, SceneFile};
use crate::world::WorldError;

/// Bytes a `.npy` file may have: 2^24 instances of float64 matrices and a header.
const MAX_NPY_BYTES: u64 = (crate::world::MAX_INSTANCES as u64) * 128 + 65536;

/// One copy: its object-to-parent matrix (applied before the object's own transform) and,
/// when it names one, its material.
pub(super) struct Placement {
    pub matrix: Mat4,
    pub material: Option<String>,
}

/// The object-to-world transform of each copy of `instances` object `object` of `file`,
/// composed and checked as its build does them ([`Builder::object`]), each also checked by
/// `check` (`World::check_move`, as the build's `add_instance` checks it), reading its `.npy`
/// file if it has one; `None` for another type of object, and for copies of a glTF file (made
/// of its nodes).
pub(crate) fn copy_transforms(
    file: &SceneFile,
    object: usize,
    mut check: impl FnMut(usize, &Transform) -> std::result::Result<(), WorldError>,
) -> Result<Option<Vec<Transform>>> {
    let Some(o) = file.desc.objects.get(object) else {
        return Ok(None);
    };
    let ShapeDesc::Instances(d) = &o.shape else {
        return Ok(None);
    };
    if super::gltf::gltf_file(o).is_some() {
        return Ok(None);
    }
    // Nothing is added to a world, so no memory bound is read (a move asks on every call).
    let mut b = Builder::new(file, None, None);
    let path = KeyPath::root("objects").index(object);
    let world = b.object_transform(&path, o)?;
    let at = path.key("transforms");
    let placements = b.placements(&path, &d.transforms)?;
    let copies = placements.iter().enumerate();
    let transforms = copies.map(|(i, p)| {
        let transform = b.copy_transform(&at.index(i), &world, p)?;
        check(i, &transform).map_err(|e| b.world_error(&at.index(i), e))?;
        Ok(transform)
    });
    Ok(Some(transforms.collect::<Result<_>>()?))
}

/// The error of a world's scale `problem`, at the key the build names for it.
pub(crate) fn scale_error(file: &SceneFile, problem: Problem) -> SceneError {
    let path = match &problem {
        Problem::Camera(_, _) if file.desc.camera.is_some() => {
            KeyPath::root("camera").key("position")
        }
        Problem::Camera(name, _) => KeyPath::root("cameras").key(name).key("position"),
        Problem::Light(i, _) => KeyPath::root("lights").index(*i),
        Problem::Tiny(_) => KeyPath::root("objects"),
    };
    file.error(ErrorKind::BadValue, &path, problem.to_string())
}

impl Builder<'_> {
    /// For each OBJ file (by identity), how many copies of it the scene's objects place: one
    /// per `mesh` object and one per placement of an `instances` object.
    pub(super) fn count_uses(&mut self, objects: &[ObjectDesc]) -> HashMap<PathBuf, usize> {
        let mut uses = HashMap::new();
        for (i, o) in objects.iter().enumerate() {
            let (file, copies) = match &o.shape {
                ShapeDesc::Mesh(m) => (&m.file, 1),
                ShapeDesc::Instances(d) => {
                    let path = KeyPath::root("objects").index(i).key("transforms");
                    let copies = match &d.transforms {
                        TransformsDesc::List(list) => list.len(),
                        // A file that cannot be read counts for none here; its error comes
                        // in order when the object is built.
                        TransformsDesc::Npy(f) => self.npy(&path, f).map_or(0, |m| m.len()),
                    };
                    (&d.file, copies)
                }
                _ => continue,
            };
            let key = self.file.files().identity(&self.file.resolve(file));
            *uses.entry(key).or_insert(0) += copies;
        }
        uses
    }

    /// The placements of an `instances` object at `path`.
    pub(super) fn placements(
        &mut self,
        path: &KeyPath,
        transforms: &TransformsDesc,
    ) -> Result<Vec<Placement>> {
        let at = path.key("transforms");
        match transforms {
            TransformsDesc::List(list) => list
                .iter()
                .enumerate()
                .map(|(i, p)| self.placement(&at.index(i), p))
                .collect(),
            TransformsDesc::Npy(file) => {
                let matrices = self.npy(&at, file)?;
                Ok(matrices
                    .iter()
                    .map(|&m| Placement {
                        matrix: m,
                        material: None,
                    })
                    .collect())
            }
        }
    }

    /// One inline placement, checked.
    fn placement(&self, at: &KeyPath, p: &PlacementDesc) -> Result<Placement> {
        Ok(Placement {
            matrix: self.own_matrix(at, (p.scale, p.rotate, p.translate), p.matrix.as_ref())?,
            material: p.material.clone(),
        })
    }

    /// The transform an object or placement at `at` gives itself: its `scale`, `rotate` and
    /// `translate` (`T·Rz·Ry·Rx·S`), or its `matrix` (by rows), checked: given alone, and
    /// affine.
    pub(super) fn own_matrix(
        &self,
        at: &KeyPath,
        (scale, rotate, translate): (Option<ColorDesc>, Option<Vec3Desc>, Option<Vec3Desc>),
        matrix: Option<&Matrix>,
    ) -> Result<Mat4> {
        let Some(rows) = matrix else {
            return Ok(srt_matrix(
                scale.map_or(Vec3::ONE, |s| s.rgb()),
                rotate.map_or(Vec3::ZERO, |r| r.vec3()),
                translate.map_or(Vec3::ZERO, |t| t.vec3()),
            ));
        };
        if scale.is_some() || rotate.is_some() || translate.is_some() {
            return Err(self.bad(
                &at.key("matrix"),
                "a matrix replaces scale, rotate and translate: give one or the other",
            ));
        }
        if rows[3].map(|v| v.0) != [0.0, 0.0, 0.0, 1.0] {
            return Err(self.bad(
                &at.key("matrix"),
                "the matrix is not affine: its last row must be [0, 0, 0, 1]",
            ));
        }
        let by_rows: Vec<f32> = rows.iter().flatten().map(|v| v.f32()).collect();
        Ok(Mat4::from_cols_slice(&by_rows).transpose())
    }

    /// The matrices of the `.npy` file `file` (named at `path`), read once per scene.
    fn npy(&mut self, path: &KeyPath, file: &str) -> Result<Rc<[Mat4]>> {
        let resolved = self.reference(path, file, ErrorKind::Asset(AssetKind::Transforms))?;
        let key = self.file.files().identity(&resolved);
        if let Some(m) = self.transforms.get(&key) {
            return Ok(m.clone());
        }
        let fail = |b: &Self, message: String| {
            b.err(
                ErrorKind::Asset(AssetKind::Transforms),
                path,
                format!(
                    "cannot load transforms \"{}\": {message}",
                    resolved.display()
                ),
            )
        };
        // Every matrix takes at least 64 bytes of the file; refuse before reading one that
        // could not fit.
        if let Some(size) = self.file.files().size(&resolved) {
            let most = size / 64;
            if most > crate::world::MAX_INSTANCES as u64 {
                let message = format!(
                    "its {size} bytes hold up to {most} matrices; a scene places at most {}",
                    crate::world::MAX_INSTANCES
                );
                return Err(fail(self, message));
            }
            let need = size + most * BYTES_PER_INSTANCE;
            if let Some(left) = self.budget.left().filter(|&left| need > left) {
                let message = format!(
                    "placing its matrices needs about {} of memory, more than the {} available",
                    crate::memory::human(need),
                    crate::memory::human(left)
                );
                return Err(fail(self, message));
            }
        }
        let bytes = self
            .file
            .files()
            .read(&resolved, MAX_NPY_BYTES)
            .map_err(|e| fail(self, e.to_string()))?;
        let matrices = npy::header(&bytes)
            .and_then(|h| npy::matrices(&bytes, &h))
            .map_err(|e| fail(self, e.to_string()))?;
        self.read.insert(resolved);
        let matrices: Rc<[Mat4]> = matrices.into();
        self.transforms.insert(key, matrices.clone());
        Ok(matrices)
    }
}
