//! [`WorldBuilder`]: a world's parts, each checked as it is added, then built.

use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;

use super::{mesh_bounds, Placed, World, WorldError, MAX_TRIANGLES};
use crate::accel::{Levels, Parts};
use crate::camera::Camera;
use crate::geometry::{Geometry, Mesh};
use crate::light::Light;
use crate::material::Material;
use crate::math::{Aabb, Transform};
use crate::pool::thread_pool;
use crate::scale;
use crate::texture::Texture;

/// Most instances in a world: some 300 bytes each with the top-level tree, so 2^24 need
/// about 5 GiB.
pub const MAX_INSTANCES: usize = 1 << 24;

/// The most triangles a mesh's uses may copy and still be copied (flattened) rather than
/// instanced: 2^20 triangles, about 100 MiB (see [`flatten_instances`]).
pub const FLATTEN_TRIANGLES: usize = 1 << 20;

/// Whether a mesh of `triangles` triangles used `uses` times should be copied into the world
/// once per use ([`WorldBuilder::add_mesh`]) rather than built once and instanced
/// ([`WorldBuilder::add_shared_mesh`], [`WorldBuilder::add_instance`]): when it is used once,
/// or when all its copies together hold at most [`FLATTEN_TRIANGLES`]. Copies cost memory;
/// instances cost a second walk per ray and leave the renderer's SIMD packets, so a copy is
/// faster wherever it fits.
pub fn flatten_instances(triangles: usize, uses: usize) -> bool {
    uses <= 1 || triangles.saturating_mul(uses) <= FLATTEN_TRIANGLES
}

/// Collects a world's parts, checking each as it is added; [`WorldBuilder::build`] then
/// builds the acceleration structure.
#[derive(Debug)]
pub struct WorldBuilder {
    geometry: Geometry,
    meshes: Vec<Mesh>,
    /// Bounds of each shared mesh's vertices, in object space.
    mesh_boxes: Vec<Aabb>,
    placed: Vec<Placed>,
    instance_materials: Vec<u32>,
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
            meshes: Vec::new(),
            mesh_boxes: Vec::new(),
            placed: Vec::new(),
            instance_materials: Vec::new(),
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
        let cutout = material.cutout.and_then(|c| c.texture);
        for index in material.texture.into_iter().chain(cutout) {
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
        self.check_materials(materials)?;
        check_indices(mesh)?;
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

    /// Adds `mesh` in its own (object) space to be built once and placed by
    /// [`WorldBuilder::add_instance`]; returns its mesh index. It is not an object and is
    /// not seen until placed.
    pub fn add_shared_mesh(&mut self, mesh: Mesh) -> Result<u32, WorldError> {
        check_indices(&mesh)?;
        if mesh.positions.iter().any(|p| !p.is_finite()) {
            return Err(WorldError::NotFinite);
        }
        self.mesh_boxes.push(mesh_bounds(&mesh));
        self.meshes.push(mesh);
        Ok(self.meshes.len() as u32 - 1)
    }

    /// Places the shared mesh `mesh` by `transform` (any invertible affine map, mirrors
    /// included) as a new object; returns its id. Its material slots map to `materials` as
    /// [`WorldBuilder::add_mesh`]'s do. The mesh is not copied: rays enter it in object space.
    pub fn add_instance(
        &mut self,
        mesh: u32,
        transform: &Transform,
        materials: &[u32],
    ) -> Result<u32, WorldError> {
        let Some(&bounds) = self.mesh_boxes.get(mesh as usize) else {
            return Err(WorldError::UnknownMesh {
                index: mesh,
                meshes: self.meshes.len(),
            });
        };
        self.check_materials(materials)?;
        check_placement(bounds, transform)?;
        if self.placed.len() >= MAX_INSTANCES {
            return Err(WorldError::TooManyInstances);
        }
        // Copies of one object share their materials' entry.
        let last = self.placed.last().map(|p| p.materials);
        let first = match last {
            Some((first, count)) if self.materials_at(first, count) == materials => first,
            _ => {
                self.instance_materials.extend_from_slice(materials);
                (self.instance_materials.len() - materials.len()) as u32
            }
        };
        let object = self.objects;
        self.placed.push(Placed {
            mesh,
            transform: *transform,
            object,
            materials: (first, materials.len() as u32),
        });
        self.objects += 1;
        Ok(object)
    }

    /// Objects added so far: the id the next one takes.
    pub fn object_count(&self) -> u32 {
        self.objects
    }

    /// The instance materials `first .. first + count`.
    fn materials_at(&self, first: u32, count: u32) -> &[u32] {
        &self.instance_materials[first as usize..(first + count) as usize]
    }

    /// `Err` naming the first of `materials` that does not exist.
    fn check_materials(&self, materials: &[u32]) -> Result<(), WorldError> {
        match materials
            .iter()
            .find(|&&i| i as usize >= self.materials.len())
        {
            Some(&index) => Err(WorldError::UnknownMaterial {
                index,
                materials: self.materials.len(),
            }),
            None => Ok(()),
        }
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
        let meshes = (&self.meshes[..], &self.mesh_boxes[..], &self.placed[..]);
        scale_problem(&self.geometry, meshes, &self.cameras, &self.lights)
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
        let parts = Parts {
            geometry: &self.geometry,
            meshes: &self.meshes,
            instances: self
                .placed
                .iter()
                .map(|p| {
                    (
                        p.mesh,
                        p.transform,
                        self.materials_at(p.materials.0, p.materials.1),
                    )
                })
                .collect(),
            materials: &self.materials,
            textures: &self.textures,
        };
        let accel = Levels::build(&parts, pool);
        World {
            geometry: Arc::new(self.geometry),
            meshes: self.meshes.into(),
            mesh_boxes: self.mesh_boxes,
            placed: self.placed,
            instance_materials: self.instance_materials,
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

/// `Err` for the first triangle of `mesh` that names a vertex past its positions.
fn check_indices(mesh: &Mesh) -> Result<(), WorldError> {
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
    Ok(())
}

/// `Ok` when `transform` may place a mesh whose vertices `bounds` bounds: it is finite and
/// invertible, and puts the mesh within ±[`scale::MAX_COORDINATE`].
pub(super) fn check_placement(bounds: Aabb, transform: &Transform) -> Result<(), WorldError> {
    if transform.is_singular() || !transform.world_from_object.is_finite() {
        return Err(WorldError::SingularTransform);
    }
    let placed = bounds.transformed(transform);
    if !placed.is_empty() {
        if !(placed.min.is_finite() && placed.max.is_finite()) {
            return Err(WorldError::NotFinite);
        }
        let largest = scale::largest_coordinate(&[placed.min, placed.max]);
        if largest > scale::MAX_COORDINATE {
            return Err(WorldError::OutOfRange(largest));
        }
    }
    Ok(())
}

/// [`WorldBuilder::scale_problem`] of a world's parts: its own triangles, its meshes with
/// their boxes and placements, its cameras and lights (a built world's as its builder's).
pub(super) fn scale_problem(
    geometry: &Geometry,
    (meshes, mesh_boxes, placed): (&[Mesh], &[Aabb], &[Placed]),
    cameras: &[(String, Camera)],
    lights: &[Light],
) -> Option<scale::Problem> {
    if geometry.is_empty() && placed.is_empty() {
        return None;
    }
    let mut reach = scale::Reach::of(geometry);
    let mut uses = vec![Vec::new(); meshes.len()];
    for p in placed {
        uses[p.mesh as usize].push(p);
    }
    for ((mesh, bounds), uses) in meshes.iter().zip(mesh_boxes).zip(uses) {
        let edge = scale::longest_edge(
            mesh.indices
                .iter()
                .map(|t| t.map(|v| mesh.positions[v as usize])),
        );
        for p in uses {
            reach = reach.with(
                bounds.transformed(&p.transform),
                edge * p.transform.largest_stretch(),
            );
        }
    }
    let camera = cameras.iter().find_map(|(name, c)| {
        let product = reach.product(c.position());
        (product > scale::MAX_REACH).then(|| scale::Problem::Camera(name.clone(), product))
    });
    let light = || {
        lights.iter().enumerate().find_map(|(i, l)| {
            let product = scale::light_points(l)
                .map(|p| reach.product(p))
                .fold(0.0, f32::max);
            (product > scale::MAX_REACH).then_some(scale::Problem::Light(i, product))
        })
    };
    let extent = || {
        let cameras = cameras.iter().map(|(_, c)| c.position());
        let bounds = cameras.fold(reach.bounds, Aabb::grow);
        let extent = (bounds.max - bounds.min).max_element();
        (extent < scale::MIN_EXTENT).then_some(scale::Problem::Tiny(extent))
    };
    camera.or_else(light).or_else(extent)
}
