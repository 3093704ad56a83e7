//! Geometries placed by a transform: a world's objects and instances
//! ([`RaycastingScene::from_world`]), and copies of a geometry
//! ([`RaycastingScene::add_instance`]).
//!
//! Ray casting copies an instance's triangles into its scene, placed by
//! [`Geometry::append`], exactly where the renderer's world puts them; rendering shares one
//! mesh among its instances, ray casting's own hierarchy does not (yet).
//!
//! A world's cut-out materials come along: every ray query (closest hit, occlusion, counting
//! and listing, and through them occupancy and the sign of the signed distance) skips a
//! crossing where the triangle's alpha test cuts it away, after the watertight test found it
//! (so a ray through the shared edge of a kept and a cut triangle hits, or not, as the
//! triangle the edge rule picks says). The closest-point queries (and distances) ignore
//! alpha: they are not rays. A copy made by [`RaycastingScene::add_instance`] keeps its
//! geometry's alpha tests; triangles added by [`RaycastingScene::add_triangles`] are opaque.

use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::lazy::{Span, Triangles};
use super::run::budget;
use super::{fits, RaycastError, RaycastingScene};
use crate::accel::AlphaTests;
use crate::geometry::{material_of, Geometry, Mesh, Triangle};
use crate::math::Transform;
use crate::scale::MAX_COORDINATE;
use crate::world::World;

/// Bytes a scene keeps per vertex (its position) and per triangle (the triangle and its
/// primitive id).
const VERTEX_BYTES: usize = 12;
const TRIANGLE_BYTES: usize = std::mem::size_of::<Triangle>() + 4;

impl RaycastingScene {
    /// The triangles of `world`, one geometry per object of the world, instances included
    /// (geometry id = object id; primitive ids count the object's triangles in the order it
    /// added them, or an instance's mesh's). An instance's triangles are copied, placed
    /// where the renderer places them. Cut-out materials come along: a ray passes through
    /// a triangle where its material's alpha test cuts it away, in every ray query (the
    /// closest-point queries ignore alpha; see the module doc).
    ///
    /// `Err(TooManyTriangles)` when the copies would hold more than
    /// [`MAX_TRIANGLES`](crate::MAX_TRIANGLES) triangles (or 2³² vertices), and
    /// `Err(OutOfMemory)` when they need more memory than the process may take.
    pub fn from_world(world: &World) -> Result<RaycastingScene, RaycastError> {
        let own = world.geometry();
        let placed = world.placed();
        let meshes = world.meshes();
        let objects = own
            .triangles
            .iter()
            .map(|t| t.object)
            .chain(placed.iter().map(|p| p.object))
            .map(|o| o + 1)
            .max()
            .unwrap_or(0);
        let (vertices, triangles) = placed
            .iter()
            .map(|p| &meshes[p.mesh as usize])
            .fold((own.positions.len(), own.len()), |(v, t), m| {
                (v + m.positions.len(), t + m.len())
            });
        fits(vertices, triangles)?;
        budget(
            &[(vertices, VERTEX_BYTES), (triangles, TRIANGLE_BYTES)],
            "the triangles",
        )?;
        let mut all = Triangles {
            geometry: Geometry {
                positions: own.positions.clone(),
                triangles: own.triangles.clone(),
                ..Geometry::default()
            },
            local_ids: local_ids(own, objects),
            spans: spans(own, objects),
            alpha: None,
        };
        for p in placed {
            let copy = place(&meshes[p.mesh as usize], &p.transform, p.object);
            all.push(
                copy.positions,
                copy.triangles.iter().map(|t| t.vertices),
                p.object,
            );
        }
        all.alpha = alpha_tests(world).map(Arc::new);
        Ok(RaycastingScene {
            triangles: Arc::new(all),
            geometries: objects,
            ..RaycastingScene::default()
        })
    }

    /// Adds a copy of geometry `geometry_id` placed by `transform`, a row-major object-to-world
    /// matrix whose last row is `[0, 0, 0, 1]` (mirrors and non-uniform scales included);
    /// returns the copy's geometry id. Its primitive ids are those of `geometry_id`'s
    /// triangles. This extends Open3D's API, which has no instances. The triangles are
    /// copied (ray casting does not share them as rendering does), so a copy costs the
    /// memory of its geometry.
    ///
    /// Nothing is added, and the error says why, when `geometry_id` is not a geometry
    /// ([`RaycastError::UnknownGeometry`]), an entry of `transform` is not finite
    /// ([`RaycastError::TransformNotFinite`]), its last row is not `[0, 0, 0, 1]`
    /// ([`RaycastError::TransformNotAffine`]), it cannot be inverted
    /// ([`RaycastError::SingularTransform`]), a placed vertex lands beyond
    /// ±[`MAX_COORDINATE`] ([`RaycastError::Beyond`], `what` = `"placed vertex"`), or the
    /// scene would hold more than [`MAX_TRIANGLES`](crate::MAX_TRIANGLES) triangles
    /// ([`RaycastError::TooManyTriangles`]).
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
        let mesh = self.triangles.mesh(geometry_id);
        let all = &self.triangles.geometry;
        fits(
            all.positions.len() + mesh.positions.len(),
            all.len() + mesh.len(),
        )?;
        let id = self.geometries;
        let copy = place(&mesh, &transform, id);
        if let Some(index) = copy.positions.iter().position(|&p| !within_range(p)) {
            return Err(RaycastError::Beyond {
                what: "placed vertex",
                index,
            });
        }
        // As in `add_triangles`: forget the structure before the triangles are changed.
        self.accel.reset();
        let triangles = Arc::make_mut(&mut self.triangles);
        let first = triangles.geometry.len();
        triangles.push(
            copy.positions,
            copy.triangles.iter().map(|t| t.vertices),
            id,
        );
        triangles.copy_alpha(geometry_id, first);
        self.geometries += 1;
        Ok(id)
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

    /// Gives the triangles from `first` on (a copy of geometry `id` just pushed) the alpha
    /// tests of `id`'s triangles, in primitive-id order.
    fn copy_alpha(&mut self, id: u32, first: usize) {
        let Some(alpha) = &mut self.alpha else {
            return;
        };
        let alpha = Arc::make_mut(alpha);
        let span = self.spans[id as usize].triangles.clone();
        let own = (span.start as usize..span.end as usize)
            .filter(|&i| self.geometry.triangles[i].object == id);
        for (k, i) in own.enumerate() {
            alpha.set_copy(first + k, i);
        }
    }

    /// Geometry `id` as a mesh of its own: its vertices, and its triangles in primitive-id
    /// order.
    fn mesh(&self, id: u32) -> Mesh {
        let Span {
            vertices,
            triangles,
        } = self.spans[id as usize].clone();
        let range = |r: std::ops::Range<u32>| r.start as usize..r.end as usize;
        Mesh {
            positions: self.geometry.positions[range(vertices.clone())].to_vec(),
            indices: self.geometry.triangles[range(triangles)]
                .iter()
                .filter(|t| t.object == id)
                .map(|t| t.vertices.map(|v| v - vertices.start))
                .collect(),
            ..Mesh::default()
        }
    }
}

/// The alpha tests of `world`'s triangles in the order `from_world` copies them (its own,
/// then each instance's mesh), or `None` when none may be cut out.
fn alpha_tests(world: &World) -> Option<AlphaTests> {
    let mut alpha = AlphaTests::of(world.materials(), world.textures())?;
    let own = world.geometry();
    for i in 0..own.len() {
        alpha.push_flat(own, i);
    }
    for p in world.placed() {
        let mesh = &world.meshes()[p.mesh as usize];
        let materials = world.instance_materials(p);
        for (i, t) in mesh.indices.iter().enumerate() {
            let uv = match mesh.has_uvs() {
                true => t.map(|v| mesh.uvs[v as usize]),
                false => Default::default(),
            };
            alpha.push_triangle(uv, material_of(mesh.slot(i), materials));
        }
    }
    alpha.any_triangle_cuts().then_some(alpha)
}

/// `mesh` placed by `transform` as object `id`, by [`Geometry::append`]: where the renderer's
/// world puts an instance's triangles.
fn place(mesh: &Mesh, transform: &Transform, id: u32) -> Geometry {
    let mut placed = Geometry::default();
    placed.append(mesh, transform, &[], id);
    placed
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

/// True when every coordinate of `p` is finite and within ±[`MAX_COORDINATE`].
fn within_range(p: Vec3) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_COORDINATE
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
