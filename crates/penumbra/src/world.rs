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

use std::time::{Duration, Instant};

use glam::Vec3;
use thiserror::Error;

use crate::accel::Bvh;
use crate::camera::Camera;
use crate::geometry::{Geometry, Hit, Mesh, Surface};
use crate::light::Light;
use crate::material::Material;
use crate::math::{Aabb, Ray, Transform};
use crate::pool::thread_pool;
use crate::scale;
use crate::texture::Texture;

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
    /// Two cameras with one name.
    #[error("a camera named \"{0}\" already exists")]
    DuplicateCamera(String),
}

/// Counts and timings of a built world.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldStats {
    /// Triangles.
    pub triangles: usize,
    /// Objects (meshes added).
    pub objects: usize,
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

/// Everything a render sees: immutable once built, and shareable between threads.
#[derive(Debug)]
pub struct World {
    geometry: Geometry,
    accel: Bvh,
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

    /// The acceleration structure over [`World::geometry`].
    pub fn accel(&self) -> &Bvh {
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

    /// Bounds of every vertex used by a triangle (empty for an empty world).
    pub fn bounds(&self) -> Aabb {
        self.geometry.bounds()
    }

    /// The closest hit with `t` in `(t_min, t_max)`.
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        self.accel.intersect(ray, t_min, t_max)
    }

    /// The surface at `hit` (a hit of this world's geometry).
    pub fn surface(&self, hit: &Hit) -> Surface {
        Surface::from_hit(&self.geometry, hit)
    }

    /// Counts and timings.
    pub fn stats(&self) -> WorldStats {
        WorldStats {
            triangles: self.geometry.len(),
            objects: self.objects as usize,
            lights: self.lights.len(),
            materials: self.materials.len() - 1,
            textures: self.textures.len(),
            cameras: self.cameras.len(),
            bvh_nodes: self.accel.node_count(),
            bvh_build_time: self.bvh_build_time,
        }
    }
}

/// Collects a world's parts, checking each as it is added; [`WorldBuilder::build`] then
/// builds the acceleration structure.
#[derive(Debug)]
pub struct WorldBuilder {
    geometry: Geometry,
    materials: Vec<Material>,
    textures: Vec<Texture>,
    lights: Vec<Light>,
    cameras: Vec<(String, Camera)>,
    objects: u32,
}

impl Default for WorldBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl WorldBuilder {
    /// An empty world with only the default material.
    pub fn new() -> Self {
        Self {
            geometry: Geometry::default(),
            materials: vec![Material::default()],
            textures: Vec::new(),
            lights: Vec::new(),
            cameras: Vec::new(),
            objects: 0,
        }
    }

    /// Adds a texture; returns its index for [`Material::texture`].
    pub fn add_texture(&mut self, texture: Texture) -> u32 {
        self.textures.push(texture);
        self.textures.len() as u32 - 1
    }

    /// Adds a material; returns its index.
    pub fn add_material(&mut self, material: Material) -> Result<u32, WorldError> {
        if let Some(index) = material.texture {
            if index as usize >= self.textures.len() {
                return Err(WorldError::UnknownTexture {
                    index,
                    textures: self.textures.len(),
                });
            }
        }
        self.materials.push(material);
        Ok(self.materials.len() as u32 - 1)
    }

    /// Adds a light.
    pub fn add_light(&mut self, light: Light) {
        self.lights.push(light);
    }

    /// Adds a camera under a name of its own.
    pub fn add_camera(
        &mut self,
        name: impl Into<String>,
        camera: Camera,
    ) -> Result<(), WorldError> {
        let name = name.into();
        if self.cameras.iter().any(|(n, _)| *n == name) {
            return Err(WorldError::DuplicateCamera(name));
        }
        self.cameras.push((name, camera));
        Ok(())
    }

    /// Adds `mesh`, placed by `transform`, as a new object; returns its id. The mesh's
    /// material slot `k` becomes the material `materials[k]` (slots past the end use the last
    /// entry; no entries means the default material).
    pub fn add_mesh(
        &mut self,
        mesh: &Mesh,
        transform: &Transform,
        materials: &[u32],
    ) -> Result<u32, WorldError> {
        for &index in materials {
            if index as usize >= self.materials.len() {
                return Err(WorldError::UnknownMaterial {
                    index,
                    materials: self.materials.len(),
                });
            }
        }
        let vertices = mesh.positions.len();
        for (triangle, tri) in mesh.indices.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= vertices) {
                return Err(WorldError::VertexOutOfRange {
                    triangle,
                    index,
                    vertices,
                });
            }
        }
        if self.geometry.len() + mesh.len() > MAX_TRIANGLES {
            return Err(WorldError::TooManyTriangles);
        }
        let (first_vertex, first_triangle) = (self.geometry.positions.len(), self.geometry.len());
        let object = self.objects;
        self.geometry.append(mesh, transform, materials, object);
        if self.geometry.positions[first_vertex..]
            .iter()
            .any(|p| !p.is_finite())
        {
            self.geometry.truncate(first_vertex, first_triangle);
            return Err(WorldError::NotFinite);
        }
        let largest = scale::largest_coordinate(&self.geometry.positions[first_vertex..]);
        if largest > scale::MAX_COORDINATE {
            self.geometry.truncate(first_vertex, first_triangle);
            return Err(WorldError::OutOfRange(largest));
        }
        self.objects += 1;
        Ok(object)
    }

    /// Adds the triangles `indices` over the world-space `vertices` with one material, as a
    /// new object; returns its id.
    pub fn add_triangles(
        &mut self,
        vertices: &[[f32; 3]],
        indices: &[[u32; 3]],
        material: u32,
    ) -> Result<u32, WorldError> {
        let mesh = Mesh {
            positions: vertices.iter().map(|&p| Vec3::from(p)).collect(),
            indices: indices.to_vec(),
            ..Mesh::default()
        };
        self.add_mesh(&mesh, &Transform::IDENTITY, &[material])
    }

    /// Where the world leaves the scales it renders exactly (see [`scale`]): the first
    /// camera (by name) or light (by index) too far from the triangles for their size, or an
    /// extent too small. `None` when all is well, or without triangles.
    pub(crate) fn scale_problem(&self) -> Option<scale::Problem> {
        if self.geometry.is_empty() {
            return None;
        }
        let reach = scale::Reach::of(&self.geometry);
        let camera = self.cameras.iter().find_map(|(name, c)| {
            let product = reach.product(c.position());
            (product > scale::MAX_REACH).then(|| scale::Problem::Camera(name.clone(), product))
        });
        let light = || {
            self.lights.iter().enumerate().find_map(|(i, l)| {
                let product = scale::light_points(l)
                    .map(|p| reach.product(p))
                    .fold(0.0, f32::max);
                (product > scale::MAX_REACH).then_some(scale::Problem::Light(i, product))
            })
        };
        let extent = || {
            let cameras = self.cameras.iter().map(|(_, c)| c.position());
            let bounds = cameras.fold(reach.bounds, Aabb::grow);
            let extent = (bounds.max - bounds.min).max_element();
            (extent < scale::MIN_EXTENT).then_some(scale::Problem::Tiny(extent))
        };
        camera.or_else(light).or_else(extent)
    }

    /// Builds the acceleration structure with `threads` workers (0: all cores) and returns
    /// the finished world.
    pub fn build(self, threads: usize) -> World {
        // Without a pool of its own (the system refused threads) the build runs serially: the
        // library never borrows rayon's global pool.
        let pool = thread_pool(threads).ok().map(|(pool, _)| pool);
        self.build_on(pool.as_ref())
    }

    /// [`WorldBuilder::build`] on the threads of `pool`, or on the calling thread without one.
    pub(crate) fn build_on(self, pool: Option<&rayon::ThreadPool>) -> World {
        let start = Instant::now();
        let accel = match pool {
            Some(pool) => Bvh::build_parallel(&self.geometry, pool),
            None => Bvh::build(&self.geometry),
        };
        World {
            geometry: self.geometry,
            accel,
            materials: self.materials,
            textures: self.textures,
            lights: self.lights,
            cameras: self.cameras,
            objects: self.objects,
            bvh_build_time: start.elapsed(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
