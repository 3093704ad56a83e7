//! Geometries placed by a transform: a world's objects and instances
//! ([`RaycastingScene::from_world`]), and placed copies of a geometry
//! ([`RaycastingScene::add_instance`]).
//!
//! A placed geometry is not copied: its mesh is built once into a tree of its own and each
//! placement enters it through its inverse (`accel::wide::levels`), as the renderer's
//! instances do. A world's trees are not built again either: its own tree and its meshes'
//! trees are viewed eight children at a time as they are.
//!
//! A world's cut-out materials come along: every ray query (closest hit, occlusion, counting
//! and listing, and through them occupancy and the sign of the signed distance) skips a
//! crossing where the triangle's alpha test cuts it away, after the watertight test found it
//! (so a ray through the shared edge of a kept and a cut triangle hits, or not, as the
//! triangle the edge rule picks says). The closest-point queries (and distances) ignore
//! alpha: they are not rays. A placement made by [`RaycastingScene::add_instance`] keeps its
//! geometry's alpha tests; triangles added by [`RaycastingScene::add_triangles`] are opaque.

use std::collections::HashMap;
use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::lazy::{LazyAccel, MeshTree, Span, Triangles};
use super::{RaycastError, RaycastingScene, INVALID_ID};
use crate::accel::placed::Placement;
use crate::accel::wide::levels::WideLevels;
use crate::accel::wide::WideBvh;
use crate::accel::{AlphaTests, Bvh};
use crate::geometry::{Geometry, Mesh, Triangle};
use crate::math::Transform;
use crate::scale::MAX_COORDINATE;
use crate::world::World;

impl RaycastingScene {
    /// The triangles of `world`, one geometry per object of the world, instances included
    /// (geometry id = object id; primitive ids count the object's triangles in the order it
    /// added them, or an instance's mesh's). An instance places its mesh's tree, as in the
    /// renderer; the world's trees are used as they are, not built again (with cut-out
    /// materials, its opaque and cut-out trees are joined under one new root, or built again
    /// as one where that root would make a tree deeper than a build makes one). Cut-out
    /// materials come along: a ray passes through a triangle where its material's alpha test
    /// cuts it away, in every ray query (the closest-point queries ignore alpha; see the
    /// module doc).
    pub fn from_world(world: &World) -> Result<RaycastingScene, RaycastError> {
        let own = world.geometry();
        // Every object is a geometry, those without triangles too (an empty mesh), so that
        // the ids of geometries added later are no object's.
        let objects = world.stats().objects as u32;
        let local_ids = local_ids(own, objects);
        let mut all = Triangles {
            geometry: Geometry {
                positions: own.positions.clone(),
                triangles: own.triangles.clone(),
                ..Geometry::default()
            },
            spans: spans(own, objects),
            alpha: own_alpha(world).map(Arc::new),
            meshes: mesh_trees(world),
            mesh_of: HashMap::new(),
            placed: HashMap::new(),
            placed_on: HashMap::new(),
            placements: Vec::new(),
            local_ids,
        };
        let mut alphas = HashMap::new();
        for p in world.placed() {
            let materials = world.instance_materials(p);
            let alpha = alphas
                .entry((p.mesh, materials.to_vec()))
                .or_insert_with(|| placed_alpha(world, p.mesh, materials).map(Arc::new))
                .clone();
            all.placed.insert(p.object, all.placements.len() as u32);
            all.placements.push(Placement {
                mesh: p.mesh,
                id: p.object,
                transform: p.transform,
                alpha,
            });
        }
        // The world's trees, viewed eight children at a time (see `Levels::own_tree`).
        let t = &all;
        let ids = |i: usize| [t.geometry.triangles[i].object, t.local_ids[i]];
        let flat = world.accel().own_tree(own).into_owned();
        let tree = Arc::new(WideBvh::from_bvh(flat, |i| own.corners(i), ids));
        let meshes = t.meshes.iter().map(|m| m.tree.clone()).collect();
        let levels = WideLevels::new(tree, t.alpha.clone(), meshes, t.placements.clone(), None);
        let accel = LazyAccel::default();
        accel.set(Arc::new(levels));
        Ok(RaycastingScene {
            triangles: Arc::new(all),
            geometries: objects,
            accel,
            ..RaycastingScene::default()
        })
    }

    /// Adds geometry `geometry_id` placed by `transform`, a row-major object-to-world matrix
    /// whose last row is `[0, 0, 0, 1]` (mirrors and non-uniform scales included); returns
    /// the placement's geometry id. Its primitive ids are those of `geometry_id`'s triangles.
    /// This extends Open3D's API, which has no instances. The triangles are not copied: the
    /// geometry is built once into a tree of its own (on its first placement) that every
    /// placement of it shares, so a placement costs about 150 bytes.
    ///
    /// Nothing is added, and the error says why, when `geometry_id` is not a geometry
    /// ([`RaycastError::UnknownGeometry`]), an entry of `transform` is not finite
    /// ([`RaycastError::TransformNotFinite`]), its last row is not `[0, 0, 0, 1]`
    /// ([`RaycastError::TransformNotAffine`]), it cannot be inverted
    /// ([`RaycastError::SingularTransform`]), or a placed vertex lands beyond
    /// ±[`MAX_COORDINATE`] ([`RaycastError::Beyond`], `what` = `"placed vertex"`).
    pub fn add_instance(
        &mut self,
        geometry_id: u32,
        transform: &[[f32; 4]; 4],
    ) -> Result<u32, RaycastError> {
        if geometry_id >= self.geometries {
            return Err(RaycastError::UnknownGeometry {
                id: geometry_id,
                geometries: self.geometries,
            });
        }
        let transform = checked_transform(transform)?;
        if self.geometries == INVALID_ID - 1 {
            return Err(RaycastError::TooManyTriangles);
        }
        let id = self.geometries;
        let scene = &self.triangles;
        // A placement of a placement places the same mesh, the two maps composed; an own
        // geometry is built into a mesh tree on its first placement.
        let (mesh, transform, alpha) = match scene.placed.get(&geometry_id) {
            Some(&p) => {
                let p = &scene.placements[p as usize];
                (Ok(p.mesh), on(&transform, p), p.alpha.clone())
            }
            None => match scene.mesh_of.get(&geometry_id) {
                Some((m, alpha)) => (Ok(*m), transform, alpha.clone()),
                None => {
                    let alpha = scene.own_alpha_of(geometry_id).map(Arc::new);
                    (Err(scene.mesh_tree(geometry_id)), transform, alpha)
                }
            },
        };
        let tree = match &mesh {
            Ok(m) => &scene.meshes[*m as usize],
            Err(tree) => tree,
        };
        check_placed(tree, &transform)?;
        // As in `add_triangles`: forget the structure before the triangles are changed.
        self.accel.reset();
        let scene = Arc::make_mut(&mut self.triangles);
        let mesh = mesh.unwrap_or_else(|tree| {
            scene.meshes.push(tree);
            let m = scene.meshes.len() as u32 - 1;
            scene.mesh_of.insert(geometry_id, (m, alpha.clone()));
            m
        });
        if scene.placed.contains_key(&geometry_id) {
            scene.placed_on.insert(id, geometry_id);
        }
        scene.placed.insert(id, scene.placements.len() as u32);
        scene.placements.push(Placement {
            mesh,
            id,
            transform,
            alpha,
        });
        self.geometries += 1;
        Ok(id)
    }
}

impl RaycastingScene {
    /// Moves placement `geometry_id` (an id [`RaycastingScene::add_instance`] returned, or a
    /// world's instance): its object-to-world transform becomes `transform` (row-major, as
    /// `add_instance` takes it), replacing the old one, not composed with it. Nothing is
    /// built again but the top level, on the next query; the queries then answer as a fresh
    /// `add_instance` with that transform would. For a placement of a placement, `transform`
    /// places the placed geometry as `add_instance` was given it, composed with where that
    /// placement is now.
    ///
    /// Refused, with nothing changed, as `add_instance` refuses a transform, and with
    /// [`RaycastError::NotAPlacement`] for an id that is no placement.
    pub fn set_transform(
        &mut self,
        geometry_id: u32,
        transform: &[[f32; 4]; 4],
    ) -> Result<(), RaycastError> {
        let Some(&index) = self.triangles.placed.get(&geometry_id) else {
            return Err(RaycastError::NotAPlacement {
                id: geometry_id,
                geometries: self.geometries,
            });
        };
        let given = checked_transform(transform)?;
        let scene = &self.triangles;
        let p = &scene.placements[index as usize];
        let transform = match scene.placed_on.get(&geometry_id) {
            Some(base) => on(&given, &scene.placements[scene.placed[base] as usize]),
            None => given,
        };
        check_placed(&scene.meshes[p.mesh as usize], &transform)?;
        self.accel.moved();
        Arc::make_mut(&mut self.triangles).placements[index as usize].transform = transform;
        Ok(())
    }
}

impl Triangles {
    /// Appends geometry `id`: `positions`, and `triangles` indexing them (the primitive ids
    /// are their indices). Its span is recorded at `id`.
    pub(super) fn push(
        &mut self,
        positions: impl IntoIterator<Item = Vec3>,
        triangles: impl IntoIterator<Item = [u32; 3]>,
        id: u32,
    ) {
        let (base, first) = (self.geometry.positions.len() as u32, self.geometry.len());
        self.geometry.positions.extend(positions);
        self.geometry
            .triangles
            .extend(triangles.into_iter().map(|t| Triangle {
                vertices: t.map(|v| base + v),
                material: 0,
                object: id,
                smooth: false,
            }));
        let count = self.geometry.len() - first;
        self.local_ids.extend(0..count as u32);
        if let Some(alpha) = &mut self.alpha {
            let alpha = Arc::make_mut(alpha);
            for _ in 0..count {
                alpha.push_triangle([Default::default(); 3], u32::MAX);
            }
        }
        let id = id as usize;
        if self.spans.len() <= id {
            self.spans.resize(id + 1, Span::default());
        }
        self.spans[id] = Span {
            vertices: base..self.geometry.positions.len() as u32,
            triangles: first as u32..self.geometry.len() as u32,
        };
    }

    /// The triangle indices of own geometry `id`, in primitive-id order.
    fn own_triangles(&self, id: u32) -> impl Iterator<Item = usize> + '_ {
        let span = self.spans[id as usize].triangles.clone();
        (span.start as usize..span.end as usize)
            .filter(move |&i| self.geometry.triangles[i].object == id)
    }

    /// The alpha tests of own geometry `id`'s triangles in primitive-id order, when some may
    /// cut.
    fn own_alpha_of(&self, id: u32) -> Option<AlphaTests> {
        let alpha = self.alpha.as_ref()?.subset(self.own_triangles(id));
        alpha.any_triangle_cuts().then_some(alpha)
    }

    /// The tree of own geometry `id` as a mesh of its own.
    fn mesh_tree(&self, id: u32) -> MeshTree {
        let vertices = self.spans[id as usize].vertices.clone();
        let positions: Arc<[Vec3]> =
            self.geometry.positions[vertices.start as usize..vertices.end as usize].into();
        let mesh = Mesh {
            positions: positions.to_vec(),
            indices: self
                .own_triangles(id)
                .map(|i| {
                    self.geometry.triangles[i]
                        .vertices
                        .map(|v| v - vertices.start)
                })
                .collect(),
            ..Mesh::default()
        };
        let mut geometry = Geometry::default();
        geometry.append(&mesh, &Transform::IDENTITY, &[], 0);
        let ids: Vec<u32> = (0..mesh.len() as u32).collect();
        MeshTree::new(Arc::new(WideBvh::build(&geometry, &ids, None)), positions)
    }
}

/// The transform of a row-major 4×4 object-to-world matrix: finite, affine (last row
/// `[0, 0, 0, 1]`) and invertible.
pub(super) fn checked_transform(rows: &[[f32; 4]; 4]) -> Result<Transform, RaycastError> {
    if let Some(i) = rows.iter().flatten().position(|v| !v.is_finite()) {
        return Err(RaycastError::TransformNotFinite {
            row: i / 4,
            column: i % 4,
        });
    }
    if rows[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(RaycastError::TransformNotAffine);
    }
    let transform = Transform::from_matrix(Mat4::from_cols_array_2d(rows).transpose());
    if transform.is_singular() {
        return Err(RaycastError::SingularTransform);
    }
    Ok(transform)
}

/// `transform` applied after placement `base`'s: a placement of a placement.
fn on(transform: &Transform, base: &Placement) -> Transform {
    Transform::from_matrix(transform.world_from_object * base.transform.world_from_object)
}

/// `Err` when `transform` is singular, or `Err(Beyond)` naming the first vertex of `mesh`
/// (used by a triangle or not) that it places beyond ±[`MAX_COORDINATE`] (or not finite). A
/// bound is looked at first: when the farthest any vertex can be placed, `Σⱼ|mᵢⱼ|·r + |tᵢ|`
/// for the vertices' reach `r`, stays within the limit with room for the rounding, so does
/// every vertex.
fn check_placed(mesh: &MeshTree, transform: &Transform) -> Result<(), RaycastError> {
    // A product of two placements' maps may be singular where neither is.
    if transform.is_singular() {
        return Err(RaycastError::SingularTransform);
    }
    let m = transform.world_from_object;
    let linear = m.x_axis.truncate().abs() + m.y_axis.truncate().abs() + m.z_axis.truncate().abs();
    let placed = (linear * mesh.reach + m.w_axis.truncate().abs()).max_element();
    if placed <= MAX_COORDINATE * (1.0 - 1.0 / 1_048_576.0) {
        return Ok(());
    }
    match mesh
        .positions
        .iter()
        .position(|&p| !within_range(transform.point(p)))
    {
        Some(index) => Err(RaycastError::Beyond {
            what: "placed vertex",
            index,
        }),
        None => Ok(()),
    }
}

/// True when every coordinate of `p` is finite and within ±[`MAX_COORDINATE`].
fn within_range(p: Vec3) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_COORDINATE
}

/// The alpha tests of `world`'s own triangles, or `None` when none may be cut out.
fn own_alpha(world: &World) -> Option<AlphaTests> {
    let mut alpha = AlphaTests::of(world.materials(), world.textures())?;
    let own = world.geometry();
    for i in 0..own.len() {
        alpha.push_flat(own, i);
    }
    alpha.any_triangle_cuts().then_some(alpha)
}

/// The alpha tests of mesh `mesh`'s triangles placed with `materials`, or `None` when none
/// may be cut out: the renderer's ([`AlphaTests::of_placement`]).
fn placed_alpha(world: &World, mesh: u32, materials: &[u32]) -> Option<AlphaTests> {
    let alpha = AlphaTests::of(world.materials(), world.textures())?;
    alpha.of_placement(&world.meshes()[mesh as usize], materials)
}

/// The trees of `world`'s meshes: the world's own, viewed eight children at a time.
fn mesh_trees(world: &World) -> Vec<MeshTree> {
    let trees = world.accel().instances().meshes();
    world
        .meshes()
        .iter()
        .enumerate()
        .map(|(m, mesh)| {
            let corners = |i: usize| mesh.indices[i].map(|v| mesh.positions[v as usize]);
            let tree = match trees.get(m) {
                Some(bvh) => WideBvh::from_bvh(Bvh::clone(bvh), corners, |i| [0, i as u32]),
                None => {
                    let mut geometry = Geometry::default();
                    geometry.append(mesh, &Transform::IDENTITY, &[], 0);
                    let ids: Vec<u32> = (0..mesh.len() as u32).collect();
                    WideBvh::build(&geometry, &ids, None)
                }
            };
            MeshTree::new(Arc::new(tree), mesh.positions.as_slice().into())
        })
        .collect()
}

/// For each triangle of a world's `geometry`, its index within its object.
fn local_ids(geometry: &Geometry, objects: u32) -> Vec<u32> {
    let mut counts = vec![0u32; objects as usize];
    geometry
        .triangles
        .iter()
        .map(|t| {
            let c = &mut counts[t.object as usize];
            *c += 1;
            *c - 1
        })
        .collect()
}

/// Where each object of a world's `geometry` lies: the vertices its triangles use (an
/// object's vertices are appended together), and its first to its last triangle.
fn spans(geometry: &Geometry, objects: u32) -> Vec<Span> {
    let mut spans = vec![Span::default(); objects as usize];
    for (i, t) in geometry.triangles.iter().enumerate() {
        let i = i as u32;
        let [a, b, c] = t.vertices;
        let (lo, hi) = (a.min(b).min(c), a.max(b).max(c) + 1);
        let s = &mut spans[t.object as usize];
        if s.triangles.is_empty() {
            *s = Span {
                vertices: lo..hi,
                triangles: i..i + 1,
            };
        } else {
            s.vertices = s.vertices.start.min(lo)..s.vertices.end.max(hi);
            s.triangles.end = i + 1;
        }
    }
    spans
}
