//! The world: everything a render sees and nothing of how it is seen. Geometry with its
//! acceleration structure, materials, textures, lights and every camera by name, built once and
//! then immutable and shared (`World` is `Send + Sync`; wrap it in an `Arc` to share it).
//! Film size, sampler, samples and seed are chosen per render call, so rendering another view
//! of the same world costs no reload and no rebuild.
//!
//! A world is built by a [`WorldBuilder`], from a scene file (see `scene`) or directly from
//! data:
//!
//! ```
//! use penumbra::{Camera, Material, WorldBuilder};
//! use glam::Vec3;
//!
//! let mut b = WorldBuilder::new();
//! let red = b.add_material(Material { diffuse: Vec3::new(0.8, 0.1, 0.1), ..Material::default() })?;
//! let id = b.add_triangles(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], &[[0, 1, 2]], red)?;
//! b.add_camera("front", Camera::new(Vec3::new(0.2, 0.2, 3.0), Vec3::new(0.2, 0.2, 0.0), Vec3::Y, 40.0)?)?;
//! let world = b.build(0);
//! assert_eq!((id, world.stats().triangles), (0, 1));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::time::Duration;

use thiserror::Error;

use std::sync::Arc;

use crate::accel::Levels;
use crate::camera::Camera;
use crate::geometry::{Facet, Geometry, Hit, Mesh, Surface};
use crate::light::Light;
use crate::material::Material;
use crate::math::{Aabb, Ray};
use crate::texture::Texture;

mod builder;
mod moves;
mod objects;
mod placed;

pub use builder::{flatten_instances, WorldBuilder, FLATTEN_TRIANGLES, MAX_INSTANCES};
pub use objects::{ObjectIndex, SurfaceAttributes};
pub(crate) use placed::Placed;

/// Most triangles in a world: about 100 bytes each with the BVH, so 2^27 need some 13 GiB.
pub const MAX_TRIANGLES: usize = 1 << 27;

/// The index of the default material every builder starts with: diffuse 0.8 grey, ambient
/// equal to diffuse, no specular (the scene format's default).
pub const DEFAULT_MATERIAL: u32 = 0;

/// Why data cannot be added to a world.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum WorldError {
    /// A triangle names a vertex that does not exist.
    #[error("triangle {triangle} uses vertex {index}, but there are only {vertices} vertices")]
    VertexOutOfRange {
        /// The triangle's index in its mesh.
        triangle: usize,
        /// The vertex index it uses.
        index: u32,
        /// How many vertices the mesh has.
        vertices: usize,
    },
    /// A position is not finite, or is beyond f32's range once transformed.
    #[error("the transformed object has coordinates beyond the range of 32-bit floats")]
    NotFinite,
    /// A vertex is finite but beyond [`MAX_COORDINATE`](crate::MAX_COORDINATE).
    #[error(
        "the object has a coordinate of {0:e}; penumbra renders coordinates within ±1e12 \
         (beyond, its 32-bit ray-triangle products overflow): scale the scene down"
    )]
    OutOfRange(f32),
    /// A material index past the world's materials.
    #[error("material {index} does not exist (the world has {materials})")]
    UnknownMaterial {
        /// The index given.
        index: u32,
        /// How many materials there are.
        materials: usize,
    },
    /// A texture index past the world's textures.
    #[error("texture {index} does not exist (the world has {textures})")]
    UnknownTexture {
        /// The index given.
        index: u32,
        /// How many textures there are.
        textures: usize,
    },
    /// More triangles than fit in memory.
    #[error("the scene has more than {MAX_TRIANGLES} triangles, too many for memory")]
    TooManyTriangles,
    /// More instances than fit in memory.
    #[error("the scene has more than {MAX_INSTANCES} instances, too many for memory")]
    TooManyInstances,
    /// An instance names a mesh that was not added.
    #[error("mesh {index} does not exist (the world has {meshes})")]
    UnknownMesh {
        /// The index given.
        index: u32,
        /// How many shared meshes there are.
        meshes: usize,
    },
    /// A move names an instance that does not exist.
    #[error("instance {index} does not exist (the world has {instances})")]
    UnknownInstance {
        /// The index given.
        index: usize,
        /// How many instances there are.
        instances: usize,
    },
    /// An instance's transform cannot be inverted (a zero scale, or factors beyond f32).
    #[error("the transform cannot be inverted (a zero scale, or factors beyond about 1e±38)")]
    SingularTransform,
    /// Two cameras with one name.
    #[error("a camera named \"{0}\" already exists")]
    DuplicateCamera(String),
}

/// Counts and timings of a built world.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldStats {
    /// Triangles as rays see them: each instance counts its mesh's triangles.
    pub triangles: usize,
    /// Triangles in memory: the world's own, and each shared mesh's once.
    pub unique_triangles: usize,
    /// Objects (meshes added, instances included).
    pub objects: usize,
    /// Meshes built once and placed by instances.
    pub meshes: usize,
    /// Instances of those meshes.
    pub instances: usize,
    /// Lights.
    pub lights: usize,
    /// Materials, not counting the default one.
    pub materials: usize,
    /// Textures.
    pub textures: usize,
    /// Cameras.
    pub cameras: usize,
    /// BVH nodes.
    pub bvh_nodes: usize,
    /// Time spent building the BVH.
    pub bvh_build_time: Duration,
}

/// Everything a render sees: shareable between threads, and changed after the build only by
/// moving instances ([`World::set_transform`]).
#[derive(Clone, Debug)]
pub struct World {
    /// Shared by `Arc` (as are the meshes and the trees over them), so that a clone, such as
    /// a world with moved instances, copies only what a move changes.
    geometry: Arc<Geometry>,
    meshes: Arc<[Mesh]>,
    /// Bounds of each shared mesh's vertices, in object space.
    mesh_boxes: Vec<Aabb>,
    placed: Vec<Placed>,
    instance_materials: Vec<u32>,
    accel: Levels,
    materials: Vec<Material>,
    textures: Vec<Texture>,
    lights: Vec<Light>,
    cameras: Vec<(String, Camera)>,
    objects: u32,
    bvh_build_time: Duration,
}

impl World {
    /// All triangles in world space.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// The acceleration structure: the tree over [`World::geometry`] and the instances (a
    /// benchmark hook, see [`crate::bench`]).
    #[doc(hidden)]
    pub fn accel(&self) -> &Levels {
        &self.accel
    }

    /// Materials, indexed by a triangle's `material`; index 0 is [`DEFAULT_MATERIAL`].
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// Textures, indexed by a material's `texture`.
    pub fn textures(&self) -> &[Texture] {
        &self.textures
    }

    /// Lights.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// Cameras with their names, in the order they were added.
    pub fn cameras(&self) -> &[(String, Camera)] {
        &self.cameras
    }

    /// The camera called `name`.
    pub fn camera(&self, name: &str) -> Option<&Camera> {
        self.cameras.iter().find(|(n, _)| n == name).map(|(_, c)| c)
    }

    /// Bounds of every vertex used by a triangle of the world's own, and of each instance's
    /// mesh box placed by the instance (which holds the placed mesh, loosely when rotated);
    /// empty for an empty world.
    pub fn bounds(&self) -> Aabb {
        self.placed
            .iter()
            .map(|p| self.mesh_boxes[p.mesh as usize].transformed(&p.transform))
            .fold(self.geometry.bounds(), Aabb::union)
    }

    /// Each instance's object id, triangles (its mesh's) and bounds (its mesh's box placed,
    /// as [`World::bounds`] takes it), in the order they were added.
    pub fn instance_summary(&self) -> Vec<(u32, usize, Aabb)> {
        self.placed
            .iter()
            .map(|p| {
                let mesh = p.mesh as usize;
                let bounds = self.mesh_boxes[mesh].transformed(&p.transform);
                (p.object, self.meshes[mesh].len(), bounds)
            })
            .collect()
    }

    /// The meshes built once and placed by instances, by index.
    pub fn meshes(&self) -> &[Mesh] {
        &self.meshes
    }

    /// The instances (mesh index, transform, object id), in the order they were added.
    pub(crate) fn placed(&self) -> &[Placed] {
        &self.placed
    }

    /// The materials instance `p`'s slots map to.
    #[inline(always)]
    pub(crate) fn instance_materials(&self, p: &Placed) -> &[u32] {
        let (first, count) = (p.materials.0 as usize, p.materials.1 as usize);
        &self.instance_materials[first..first + count]
    }

    /// The closest hit with `t` in `(t_min, t_max)`.
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        self.accel.intersect(ray, t_min, t_max)
    }

    /// The surface at `hit` (a hit of this world's triangles or instances).
    #[inline(always)]
    pub fn surface(&self, hit: &Hit) -> Surface {
        self.facet(hit).at(hit)
    }

    /// The surface at `hit`, reading the triangle from `last` when it holds the hit and
    /// leaving the hit's triangle there: for hits in a row, which often share one. The same
    /// surface as [`surface`](Self::surface).
    #[inline(always)]
    pub(crate) fn surface_after(&self, hit: &Hit, last: &mut Option<Facet>) -> Surface {
        match last {
            Some(facet) if facet.holds(hit) => facet.at(hit),
            _ => last.insert(self.facet(hit)).at(hit),
        }
    }

    /// The triangle `hit` is on, as shading reads it.
    #[inline(always)]
    fn facet(&self, hit: &Hit) -> Facet {
        let Some(instance) = hit.instance else {
            return Facet::of_geometry(&self.geometry, hit);
        };
        let p = &self.placed[instance as usize];
        let (mesh, materials) = (&self.meshes[p.mesh as usize], self.instance_materials(p));
        Facet::of_instance(mesh, &p.transform, hit, p.object, materials)
    }

    /// Counts and timings.
    pub fn stats(&self) -> WorldStats {
        let placed: usize = self
            .placed
            .iter()
            .map(|p| self.meshes[p.mesh as usize].len())
            .sum();
        let shared: usize = self.meshes.iter().map(Mesh::len).sum();
        WorldStats {
            triangles: self.geometry.len() + placed,
            unique_triangles: self.geometry.len() + shared,
            objects: self.objects as usize,
            meshes: self.meshes.len(),
            instances: self.placed.len(),
            lights: self.lights.len(),
            materials: self.materials.len() - 1,
            textures: self.textures.len(),
            cameras: self.cameras.len(),
            bvh_nodes: self.accel.node_count(),
            bvh_build_time: self.bvh_build_time,
        }
    }
}

/// Bounds of the vertices `mesh`'s triangles use.
fn mesh_bounds(mesh: &Mesh) -> Aabb {
    mesh.indices
        .iter()
        .flatten()
        .map(|&v| mesh.positions[v as usize])
        .fold(Aabb::EMPTY, Aabb::grow)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::math::Transform;

    fn tri() -> [[f32; 3]; 3] {
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    }

    #[test]
    fn objects_are_numbered_in_order_and_hits_name_them() {
        let mut b = WorldBuilder::new();
        let a = b
            .add_triangles(&tri(), &[[0, 1, 2]], DEFAULT_MATERIAL)
            .unwrap();
        let moved = tri().map(|[x, y, z]| [x, y, z - 1.0]);
        let c = b
            .add_triangles(&moved, &[[0, 1, 2]], DEFAULT_MATERIAL)
            .unwrap();
        assert_eq!((a, c), (0, 1));
        let world = b.build(1);
        let ray = Ray::new(Vec3::new(0.2, 0.2, 5.0), -Vec3::Z);
        let hit = world.intersect(&ray, 0.0, f32::INFINITY).unwrap();
        assert_eq!(world.surface(&hit).object, 0);
        let ray = Ray::new(Vec3::new(0.2, 0.2, -5.0), Vec3::Z);
        let hit = world.intersect(&ray, 0.0, f32::INFINITY).unwrap();
        assert_eq!(world.surface(&hit).object, 1);
        assert_eq!(world.stats().objects, 2);
    }

    #[test]
    fn bad_data_is_refused_and_leaves_the_builder_unchanged() {
        let mut b = WorldBuilder::new();
        let e = b.add_triangles(&tri(), &[[0, 1, 3]], 0).unwrap_err();
        assert!(matches!(e, WorldError::VertexOutOfRange { index: 3, .. }));
        let e = b.add_triangles(&tri(), &[[0, 1, 2]], 5).unwrap_err();
        assert!(matches!(e, WorldError::UnknownMaterial { index: 5, .. }));
        let far = Transform::from_srt(Vec3::splat(3e38), Vec3::ZERO, Vec3::ZERO);
        let mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X * 2.0, Vec3::Y],
            indices: vec![[0, 1, 2]],
            ..Mesh::default()
        };
        assert_eq!(b.add_mesh(&mesh, &far, &[0]), Err(WorldError::NotFinite));
        let textured = Material {
            texture: Some(0),
            ..Material::default()
        };
        assert!(matches!(
            b.add_material(textured),
            Err(WorldError::UnknownTexture { index: 0, .. })
        ));
        let cam = Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0).unwrap();
        b.add_camera("a", cam).unwrap();
        assert_eq!(
            b.add_camera("a", cam),
            Err(WorldError::DuplicateCamera("a".into()))
        );
        let world = b.build(1);
        assert_eq!(world.stats().triangles, 0);
        assert_eq!(world.stats().objects, 0);
        assert!(world.bounds().is_empty());
    }

    #[test]
    fn world_is_send_and_sync() {
        fn assert_send_sync<T: Send + Sync>() {}
        assert_send_sync::<World>();
    }
}
