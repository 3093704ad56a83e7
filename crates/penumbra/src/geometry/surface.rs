//! What a ray hit, as shading and ray-casting queries need it: [`Surface::from_hit`] turns a
//! geometric [`Hit`] into the point, normals, texture coordinates, vertex colour and ids of the
//! triangle.

use glam::{Vec2, Vec3};

use super::mesh::material_of;
use super::{Geometry, Hit, Mesh};
use crate::math::{unit_cross, Rgb, Transform};

/// The surface at a ray hit, in world space. Normals are as the triangle defines them, not
/// turned toward the ray: callers that shade face-forward them, callers that cast rays (like
/// Open3D's `primitive_normals`) do not.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// The hit point, interpolated from the vertices by the barycentrics.
    pub position: Vec3,
    /// A bound on the rounding error of `position`, per axis: γ₇·Σ|bᵢ·pᵢ| (pbrt's bound for a
    /// point interpolated from a triangle's vertices), plus γ₃·(|e₁| + |e₂|) on every axis for
    /// the rounding of the ray–triangle test itself, whose terms grow with the triangle's size.
    /// Rays leaving the surface start this far off it, projected on the normal, so they clear
    /// it at any scale and distance from the origin.
    pub error: Vec3,
    /// Unit `e1 × e2` of the triangle; zero for a sliver whose cross product underflows.
    pub geometric_normal: Vec3,
    /// Unit interpolated vertex normal of a smooth triangle, else the geometric normal.
    pub shading_normal: Vec3,
    /// Interpolated texture coordinates.
    pub uv: Vec2,
    /// The interpolated vertex colour (linear RGB), exactly 1 for a triangle without vertex
    /// colours and exactly the corners' colour where all three agree.
    pub color: Rgb,
    /// Index of the triangle in [`Geometry::triangles`].
    pub triangle: u32,
    /// The object the triangle belongs to.
    pub object: u32,
    /// The triangle's material index.
    pub material: u32,
}

/// γ₇ = 7u / (1 − 7u) with u the unit roundoff of `f32` (Pharr, Jakob and Humphreys, *Physically
/// Based Rendering*, 3rd ed., §3.9): the relative error bound of a sum of three products.
const GAMMA_7: f32 = 7.0 * (f32::EPSILON / 2.0) / (1.0 - 7.0 * (f32::EPSILON / 2.0));
/// γ₃, the bound for a dot or cross product of two 3-vectors.
const GAMMA_3: f32 = 3.0 * (f32::EPSILON / 2.0) / (1.0 - 3.0 * (f32::EPSILON / 2.0));

impl Surface {
    /// The geometric and shading normals as seen along `direction` (SPEC §5): the geometric
    /// normal turned toward the ray's origin, both flipped together; then the shading normal
    /// onto the geometric normal's side. A mirroring transform (negative scale) reverses the
    /// winding, so e1 × e2 flips while the inverse-transpose vertex normals do not, and OBJ
    /// files can carry normals that disagree with their winding: either way the shading
    /// normal belongs on the viewer's side, as pbrt does by face-forwarding one to the other.
    pub fn facing(&self, direction: Vec3) -> (Vec3, Vec3) {
        let (mut n_geom, mut n) = (self.geometric_normal, self.shading_normal);
        if n_geom.dot(direction) > 0.0 {
            n_geom = -n_geom;
            n = -n;
        }
        if n.dot(n_geom) < 0.0 {
            n = -n;
        }
        (n_geom, n)
    }

    /// The surface of `geometry` at `hit` (a hit of the world's own triangles).
    #[inline(always)]
    pub fn from_hit(geometry: &Geometry, hit: &Hit) -> Surface {
        Facet::of_geometry(geometry, hit).at(hit)
    }

    /// The surface at `hit` of `mesh` placed in the world by `world` as object `object`, its
    /// material slots mapped by `materials`: the corners are transformed exactly as
    /// [`Geometry::append`] transforms a copy of the mesh, so the surface is the copy's.
    pub fn from_instance(
        mesh: &Mesh,
        world: &Transform,
        hit: &Hit,
        object: u32,
        materials: &[u32],
    ) -> Surface {
        Facet::of_instance(mesh, world, hit, object, materials).at(hit)
    }
}

/// A triangle as shading reads it: its world-space corners and what they carry, and what
/// every point on it shares (its unit normal, the part of the rounding bound that grows with
/// its size). Consecutive hits on one triangle can share one ([`Facet::holds`]): a room's wall
/// is two triangles under many thousands of pixels, and the normal's square root and
/// division wait on each other.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Facet {
    /// World-space corners.
    p: [Vec3; 3],
    /// A smooth triangle's world-space vertex normals.
    n: Option<[Vec3; 3]>,
    /// Texture coordinates of the corners.
    uv: [Vec2; 3],
    /// A coloured triangle's vertex colours.
    colors: Option<[Rgb; 3]>,
    /// The triangle, object and material ids.
    ids: (u32, u32, u32),
    /// The instance of the hits it is for.
    instance: Option<u32>,
    /// Unit `e1 × e2`.
    geometric_normal: Vec3,
    /// γ₃·(|e₁| + |e₂|), the ray–triangle test's share of [`Surface::error`].
    edge_error: f32,
}

impl Facet {
    /// The triangle of `geometry` that `hit` is on (a hit of the world's own triangles).
    #[inline(always)]
    pub(crate) fn of_geometry(geometry: &Geometry, hit: &Hit) -> Facet {
        let tri = &geometry.triangles[hit.triangle as usize];
        let [i0, i1, i2] = tri.vertices.map(|v| v as usize);
        let p = [i0, i1, i2].map(|i| geometry.positions[i]);
        let n = tri
            .smooth
            .then(|| [i0, i1, i2].map(|i| geometry.normals[i]));
        let uv = [i0, i1, i2].map(|i| geometry.uvs[i]);
        let colors =
            (!geometry.colors.is_empty()).then(|| [i0, i1, i2].map(|i| geometry.colors[i]));
        let ids = (hit.triangle, tri.object, tri.material);
        Facet::new(p, n, uv, colors, ids, hit.instance)
    }

    /// The triangle `hit` is on, of `mesh` placed by `world` as object `object` (see
    /// [`Surface::from_instance`]).
    pub(crate) fn of_instance(
        mesh: &Mesh,
        world: &Transform,
        hit: &Hit,
        object: u32,
        materials: &[u32],
    ) -> Facet {
        let index = hit.triangle as usize;
        let corners = mesh.indices[index].map(|v| v as usize);
        let p = corners.map(|v| world.point(mesh.positions[v]));
        let n = mesh
            .is_smooth()
            .then(|| corners.map(|v| world.normal(mesh.normals[v])));
        let uv = match mesh.has_uvs() {
            true => corners.map(|v| mesh.uvs[v]),
            false => [Vec2::ZERO; 3],
        };
        let colors = mesh.has_colors().then(|| corners.map(|v| mesh.colors[v]));
        let material = material_of(mesh.slot(index), materials);
        let ids = (hit.triangle, object, material);
        Facet::new(p, n, uv, colors, ids, hit.instance)
    }

    /// The facet with world-space corners `p`, vertex normals `n` (a smooth triangle's),
    /// texture coordinates `uv` and vertex colours `colors` (a coloured triangle's); `ids` are
    /// its triangle, object and material, `instance` the instance its hits are of.
    #[inline(always)]
    fn new(
        p: [Vec3; 3],
        n: Option<[Vec3; 3]>,
        uv: [Vec2; 3],
        colors: Option<[Rgb; 3]>,
        ids: (u32, u32, u32),
        instance: Option<u32>,
    ) -> Facet {
        let [p0, p1, p2] = p;
        Facet {
            p,
            n,
            uv,
            colors,
            ids,
            instance,
            geometric_normal: unit_cross(p1 - p0, p2 - p0),
            edge_error: GAMMA_3 * ((p1 - p0).length() + (p2 - p0).length()),
        }
    }

    /// Whether `hit` is on this facet (the same triangle of the same instance).
    #[inline(always)]
    pub(crate) fn holds(&self, hit: &Hit) -> bool {
        self.ids.0 == hit.triangle && self.instance == hit.instance
    }

    /// The surface at `hit`'s barycentrics (a hit the facet [`holds`](Self::holds)).
    #[inline(always)]
    pub(crate) fn at(&self, hit: &Hit) -> Surface {
        let [p0, p1, p2] = self.p;
        let (uv, geometric_normal) = (self.uv, self.geometric_normal);
        let b0 = 1.0 - hit.b1 - hit.b2;
        let shading_normal = match self.n {
            Some([n0, n1, n2]) => {
                let ns = b0 * n0 + hit.b1 * n1 + hit.b2 * n2;
                ns.try_normalize().unwrap_or(geometric_normal)
            }
            None => geometric_normal,
        };
        let (triangle, object, material) = self.ids;
        Surface {
            position: b0 * p0 + hit.b1 * p1 + hit.b2 * p2,
            error: GAMMA_7 * ((b0 * p0).abs() + (hit.b1 * p1).abs() + (hit.b2 * p2).abs())
                + Vec3::splat(self.edge_error),
            geometric_normal,
            shading_normal,
            uv: b0 * uv[0] + hit.b1 * uv[1] + hit.b2 * uv[2],
            color: match self.colors {
                // One colour at all three corners is that colour, exactly (the barycentrics'
                // sum may round off 1): uncoloured meshes in a coloured scene stay white.
                Some([c0, c1, c2]) if c0 == c1 && c1 == c2 => c0,
                Some([c0, c1, c2]) => b0 * c0 + hit.b1 * c1 + hit.b2 * c2,
                None => Rgb::ONE,
            },
            triangle,
            object,
            material,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_position_uv_and_normals_and_keeps_ids() {
        let mesh = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: vec![Vec3::Z, Vec3::Z, Vec3::X],
            uvs: vec![Vec2::ZERO, Vec2::X, Vec2::Y],
            indices: vec![[0, 1, 2]],
            ..Mesh::default()
        };
        let mut g = Geometry::default();
        g.append(&mesh, &Transform::IDENTITY, &[3], 7);
        let hit = Hit {
            t: 1.0,
            b1: 0.25,
            b2: 0.5,
            triangle: 0,
            instance: None,
        };
        let s = Surface::from_hit(&g, &hit);
        assert!((s.position - Vec3::new(0.25, 0.5, 0.0)).length() < 1e-6);
        assert!((s.uv - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert_eq!(s.geometric_normal, Vec3::Z);
        // 0.5·z + 0.5·x, normalized: not flipped toward any ray.
        assert!((s.shading_normal - Vec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-6);
        assert_eq!((s.triangle, s.object, s.material), (0, 7, 3));
        assert_eq!(s.color, Rgb::ONE);
    }

    fn hit(b1: f32, b2: f32) -> Hit {
        Hit {
            t: 1.0,
            b1,
            b2,
            triangle: 0,
            instance: None,
        }
    }

    fn colored(colors: Vec<Rgb>) -> Mesh {
        Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            colors,
            indices: vec![[0, 1, 2]],
            ..Mesh::default()
        }
    }

    #[test]
    fn interpolates_vertex_colours_and_keeps_a_uniform_one_exact() {
        let mesh = colored(vec![Rgb::X, Rgb::Y, Rgb::Z]);
        let mut g = Geometry::default();
        g.append(&mesh, &Transform::IDENTITY, &[0], 0);
        let s = Surface::from_hit(&g, &hit(0.25, 0.5));
        assert!((s.color - Rgb::new(0.25, 0.25, 0.5)).length() < 1e-6);
        // Barycentrics whose sum rounds off 1 still give a uniform colour exactly.
        let grey = Rgb::splat(0.3);
        let mut g = Geometry::default();
        g.append(&colored(vec![grey; 3]), &Transform::IDENTITY, &[0], 0);
        let (b1, b2) = (0.134_041_7_f32, 0.349_079_04_f32);
        assert_ne!((1.0 - b1 - b2) * 0.3 + b1 * 0.3 + b2 * 0.3, 0.3f32);
        assert_eq!(Surface::from_hit(&g, &hit(b1, b2)).color, grey);
    }

    #[test]
    fn an_instance_is_its_copy_bit_for_bit() {
        let mut mesh = colored(vec![Rgb::X, Rgb::new(0.2, 0.7, 0.1), Rgb::Z]);
        mesh.normals = vec![Vec3::Z, Vec3::X, Vec3::Y];
        mesh.uvs = vec![Vec2::ZERO, Vec2::X, Vec2::Y];
        let world = Transform::from_srt(
            Vec3::new(2.0, -1.0, 0.5),
            Vec3::new(10.0, 20.0, 30.0),
            Vec3::new(1.0, 2.0, 3.0),
        );
        let mut g = Geometry::default();
        g.append(&mesh, &world, &[4, 5], 9);
        for (b1, b2) in [(0.1, 0.7), (0.3, 0.3), (0.0, 1.0)] {
            let copy = Surface::from_hit(&g, &hit(b1, b2));
            let instance = Surface::from_instance(&mesh, &world, &hit(b1, b2), 9, &[4, 5]);
            assert_eq!(copy, instance);
        }
    }
}
