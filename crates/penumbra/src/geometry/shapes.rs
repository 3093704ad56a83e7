//! The built-in shapes of the scene format, each made as an object-space [`Mesh`].

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::Mesh;

/// Longitude divisions of the tessellated sphere.
pub const SPHERE_SEGMENTS: u32 = 96;
/// Latitude divisions of the tessellated sphere.
pub const SPHERE_RINGS: u32 = 48;

/// A single triangle with the given uvs (the format's default is (0,0), (1,0), (0,1)) and
/// optional vertex normals.
pub fn triangle(vertices: [Vec3; 3], uvs: [Vec2; 3], normals: Option<[Vec3; 3]>) -> Mesh {
    Mesh {
        positions: vertices.to_vec(),
        normals: normals.map(|n| n.to_vec()).unwrap_or_default(),
        uvs: uvs.to_vec(),
        indices: vec![[0, 1, 2]],
        ..Mesh::default()
    }
}

/// The parallelogram `corner`, `corner + u`, `corner + u + v`, `corner + v` as two triangles
/// wound so that `e1 × e2` points along `u × v`, with uvs (0,0), (1,0), (1,1), (0,1).
pub fn quad(corner: Vec3, u: Vec3, v: Vec3) -> Mesh {
    let mut mesh = Mesh::default();
    push_quad(&mut mesh, corner, u, v);
    mesh
}

fn push_quad(mesh: &mut Mesh, corner: Vec3, u: Vec3, v: Vec3) {
    let base = mesh.positions.len() as u32;
    mesh.positions
        .extend([corner, corner + u, corner + u + v, corner + v]);
    mesh.uvs.extend([
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
    ]);
    mesh.indices
        .extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
}

/// An axis-aligned box centered on the origin with edge lengths `size`: 12 triangles wound
/// counter-clockwise from outside. Each face's uvs span the unit square: on the side faces u
/// runs to the right and v up (+y) as seen from outside; on the top u runs along +x and v along
/// −z, on the bottom u along +x and v along +z.
pub fn cube(size: Vec3) -> Mesh {
    let h = 0.5 * size;
    let (x, y, z) = (Vec3::X * size.x, Vec3::Y * size.y, Vec3::Z * size.z);
    // (face center, u edge, v edge): u × v points outward.
    let faces = [
        (Vec3::new(0.0, 0.0, h.z), x, y),   // front (+z)
        (Vec3::new(0.0, 0.0, -h.z), -x, y), // back (−z)
        (Vec3::new(h.x, 0.0, 0.0), -z, y),  // right (+x)
        (Vec3::new(-h.x, 0.0, 0.0), z, y),  // left (−x)
        (Vec3::new(0.0, h.y, 0.0), x, -z),  // top (+y)
        (Vec3::new(0.0, -h.y, 0.0), x, z),  // bottom (−y)
    ];
    let mut mesh = Mesh::default();
    for (center, u, v) in faces {
        push_quad(&mut mesh, center - 0.5 * (u + v), u, v);
    }
    mesh
}

/// A sphere centered on the origin, tessellated into [`SPHERE_SEGMENTS`] × [`SPHERE_RINGS`]
/// quads (triangles at the poles) with smooth normals. v runs from 0 at the bottom pole (−y)
/// to 1 at the top; u is the azimuth from +x toward −z divided by 2π.
pub fn sphere(radius: f32) -> Mesh {
    let (segments, rings) = (SPHERE_SEGMENTS, SPHERE_RINGS);
    let mut mesh = Mesh::default();
    for j in 0..=rings {
        let v = j as f32 / rings as f32;
        let theta = PI * v; // polar angle from the bottom pole
        for i in 0..=segments {
            let u = i as f32 / segments as f32;
            let phi = 2.0 * PI * u;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                -theta.cos(),
                -theta.sin() * phi.sin(),
            );
            mesh.positions.push(radius * n);
            mesh.normals.push(n);
            mesh.uvs.push(Vec2::new(u, v));
        }
    }
    let row = segments + 1;
    for j in 0..rings {
        for i in 0..segments {
            let a = j * row + i; // (u, v)
            let b = a + 1; // (u + du, v)
            let c = a + row + 1; // (u + du, v + dv)
            let d = a + row; // (u, v + dv)

            // Counter-clockwise from outside. At the bottom pole a and b coincide, at the top
            // c and d do, so each pole ring keeps only its one real triangle per quad.
            if j != 0 {
                mesh.indices.push([a, b, c]);
            }
            if j != rings - 1 {
                mesh.indices.push([a, c, d]);
            }
        }
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    fn face_normal(mesh: &Mesh, t: usize) -> Vec3 {
        let [a, b, c] = mesh.indices[t].map(|i| mesh.positions[i as usize]);
        (b - a).cross(c - a).normalize()
    }

    fn centroid(mesh: &Mesh, t: usize) -> Vec3 {
        mesh.indices[t]
            .iter()
            .map(|&i| mesh.positions[i as usize])
            .sum::<Vec3>()
            / 3.0
    }

    #[test]
    fn cube_is_twelve_outward_triangles() {
        let mesh = cube(Vec3::new(2.0, 4.0, 6.0));
        assert_eq!(mesh.len(), 12);
        for t in 0..12 {
            let n = face_normal(&mesh, t);
            let c = centroid(&mesh, t);
            // Outward: the normal is the unit axis the face's centroid lies along.
            let axis = c / Vec3::new(1.0, 2.0, 3.0);
            assert!(
                (n - axis.round()).length() < 1e-5,
                "triangle {t}: {n} at {c}"
            );
        }
    }

    #[test]
    fn cube_face_uvs_follow_the_format() {
        let mesh = cube(Vec3::ONE);
        // Find the uv of a corner of the face whose normal is `n`.
        let uv_at = |n: Vec3, p: Vec3| -> Vec2 {
            for t in 0..12 {
                if (face_normal(&mesh, t) - n).length() < 1e-5 {
                    for &i in &mesh.indices[t] {
                        if (mesh.positions[i as usize] - p).length() < 1e-5 {
                            return mesh.uvs[i as usize];
                        }
                    }
                }
            }
            panic!("no corner {p} on face {n}");
        };
        let h = 0.5;
        // Front: u to +x, v to +y.
        assert_eq!(uv_at(Vec3::Z, Vec3::new(-h, -h, h)), Vec2::new(0.0, 0.0));
        assert_eq!(uv_at(Vec3::Z, Vec3::new(h, h, h)), Vec2::new(1.0, 1.0));
        // Back, seen from outside (from −z): right is −x.
        assert_eq!(uv_at(-Vec3::Z, Vec3::new(h, -h, -h)), Vec2::new(0.0, 0.0));
        // Right (+x): right is −z.
        assert_eq!(uv_at(Vec3::X, Vec3::new(h, -h, h)), Vec2::new(0.0, 0.0));
        // Left (−x): right is +z.
        assert_eq!(uv_at(-Vec3::X, Vec3::new(-h, -h, -h)), Vec2::new(0.0, 0.0));
        // Top: u along +x, v along −z.
        assert_eq!(uv_at(Vec3::Y, Vec3::new(-h, h, h)), Vec2::new(0.0, 0.0));
        assert_eq!(uv_at(Vec3::Y, Vec3::new(h, h, -h)), Vec2::new(1.0, 1.0));
        // Bottom: u along +x, v along +z.
        assert_eq!(uv_at(-Vec3::Y, Vec3::new(-h, -h, -h)), Vec2::new(0.0, 0.0));
    }

    #[test]
    fn quad_is_two_triangles_facing_u_cross_v() {
        let mesh = quad(Vec3::ZERO, Vec3::X, Vec3::Z);
        assert_eq!(mesh.len(), 2);
        for t in 0..2 {
            assert!((face_normal(&mesh, t) - Vec3::X.cross(Vec3::Z)).length() < 1e-6);
        }
    }

    #[test]
    fn sphere_points_lie_on_the_sphere_and_face_outward() {
        let mesh = sphere(2.0);
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!((p.length() - 2.0).abs() < 1e-5);
            assert!((*p / 2.0 - *n).length() < 1e-5);
        }
        for t in 0..mesh.len() {
            assert!(face_normal(&mesh, t).dot(centroid(&mesh, t)) > 0.0);
        }
        let expected = 2 * SPHERE_SEGMENTS * (SPHERE_RINGS - 1);
        assert_eq!(mesh.len() as u32, expected);
    }

    #[test]
    fn sphere_uv_convention() {
        let mesh = sphere(1.0);
        for (p, uv) in mesh.positions.iter().zip(&mesh.uvs) {
            // v = 0 at the bottom, 1 at the top.
            assert!((p.y - -(std::f32::consts::PI * uv.y).cos()).abs() < 1e-5);
        }
        // u = 0.25 is a quarter turn from +x toward −z.
        let i = mesh
            .uvs
            .iter()
            .position(|uv| (uv.x - 0.25).abs() < 1e-6 && (uv.y - 0.5).abs() < 1e-6)
            .unwrap();
        assert!((mesh.positions[i] - -Vec3::Z).length() < 1e-5);
    }
}
