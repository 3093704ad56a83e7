//! Test meshes: a subdivided icosphere and cube built here, OBJ files of `assets/`, and rays
//! aimed at points of their shared edges and at their vertices.

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat3, Vec3};

use crate::math::Transform;
use crate::sampling::Rng;

/// Vertex positions and index triples.
pub(crate) type MeshData = (Vec<[f32; 3]>, Vec<[u32; 3]>);

/// An icosahedron subdivided `levels` times, projected on the unit sphere, outward-wound.
pub(crate) fn icosphere(levels: u32) -> MeshData {
    let g = (1.0 + 5f32.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = [
        [-1.0, g, 0.0],
        [1.0, g, 0.0],
        [-1.0, -g, 0.0],
        [1.0, -g, 0.0],
        [0.0, -1.0, g],
        [0.0, 1.0, g],
        [0.0, -1.0, -g],
        [0.0, 1.0, -g],
        [g, 0.0, -1.0],
        [g, 0.0, 1.0],
        [-g, 0.0, -1.0],
        [-g, 0.0, 1.0],
    ]
    .map(|p| Vec3::from(p).normalize())
    .to_vec();
    let mut t: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut split = |a: u32, b: u32, v: &mut Vec<Vec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push((v[a as usize] + v[b as usize]).normalize());
                v.len() as u32 - 1
            })
        };
        t = t
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (
                    split(a, b, &mut v),
                    split(b, c, &mut v),
                    split(c, a, &mut v),
                );
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    (v.iter().map(|p| p.to_array()).collect(), t)
}

/// A cube `[-1, 1]³` with each face split into `n × n` squares (two triangles each),
/// rotated by `rotation`; faces wound outward.
pub(crate) fn subdivided_cube(n: u32, rotation: Mat3) -> MeshData {
    let mut index: HashMap<[i32; 3], u32> = HashMap::new();
    let mut v = Vec::new();
    let mut t = Vec::new();
    let n = n as i32;
    let mut vertex = |p: [i32; 3], v: &mut Vec<[f32; 3]>| {
        *index.entry(p).or_insert_with(|| {
            let q = Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) * (2.0 / n as f32) - 1.0;
            v.push((rotation * q).to_array());
            v.len() as u32 - 1
        })
    };
    for axis in 0..3 {
        for side in [0, n] {
            for i in 0..n {
                for j in 0..n {
                    let at = |di: i32, dj: i32| {
                        let mut p = [0; 3];
                        p[axis] = side;
                        p[(axis + 1) % 3] = i + di;
                        p[(axis + 2) % 3] = j + dj;
                        p
                    };
                    let q = [at(0, 0), at(1, 0), at(1, 1), at(0, 1)].map(|p| vertex(p, &mut v));
                    let (a, b) = if side == n {
                        ([q[0], q[1], q[2]], [q[0], q[2], q[3]])
                    } else {
                        ([q[0], q[2], q[1]], [q[0], q[3], q[2]])
                    };
                    t.extend([a, b]);
                }
            }
        }
    }
    (v, t)
}

/// Positions and triangles of an OBJ file (`v` and `f` lines; polygons as fans).
pub(crate) fn read_obj(path: &Path) -> MeshData {
    let text = std::fs::read_to_string(path).unwrap();
    let (mut v, mut t) = (Vec::new(), Vec::new());
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let p: Vec<f32> = words.take(3).map(|w| w.parse().unwrap()).collect();
                v.push([p[0], p[1], p[2]]);
            }
            Some("f") => {
                let idx: Vec<u32> = words
                    .map(|w| w.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect();
                for k in 1..idx.len() - 1 {
                    t.push([idx[0], idx[k], idx[k + 1]]);
                }
            }
            _ => {}
        }
    }
    (v, t)
}

/// The key of a position: its bits, so that equal coordinates meet.
fn key(p: [f32; 3]) -> [u32; 3] {
    p.map(f32::to_bits)
}

/// Edges (by corner positions) with the triangles using each.
pub(crate) fn edges(mesh: &MeshData) -> HashMap<([u32; 3], [u32; 3]), Vec<usize>> {
    let mut e: HashMap<_, Vec<usize>> = HashMap::new();
    for (i, tri) in mesh.1.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (
                key(mesh.0[tri[k] as usize]),
                key(mesh.0[tri[(k + 1) % 3] as usize]),
            );
            e.entry((a.min(b), a.max(b))).or_default().push(i);
        }
    }
    e
}

/// A point to aim at and the triangles that hold it.
pub(crate) struct Target {
    pub point: Vec3,
    pub triangles: Vec<usize>,
}

/// Points on every edge shared by exactly two triangles (midpoint, a third, a tenth of the
/// way) and every vertex used by a triangle and not on a hole's rim, with the triangles around them.
pub(crate) fn targets(mesh: &MeshData) -> Vec<Target> {
    let from = |k: [u32; 3]| Vec3::from(k.map(f32::from_bits));
    let all = edges(mesh);
    // Vertices on a hole's rim or a non-manifold edge: a ray may pass by them legitimately.
    let rim: std::collections::HashSet<[u32; 3]> = all
        .iter()
        .filter(|(_, t)| t.len() != 2)
        .flat_map(|(&(a, b), _)| [a, b])
        .collect();
    let mut shared: Vec<_> = all.into_iter().filter(|(_, t)| t.len() == 2).collect();
    shared.sort();
    let mut out: Vec<Target> = Vec::new();
    for ((a, b), tris) in shared {
        let (a, b) = (from(a), from(b));
        for s in [0.5, 1.0 / 3.0, 0.1] {
            out.push(Target {
                point: a + s * (b - a),
                triangles: tris.clone(),
            });
        }
    }
    let mut around: HashMap<[u32; 3], Vec<usize>> = HashMap::new();
    for (i, tri) in mesh.1.iter().enumerate() {
        for &v in tri {
            around.entry(key(mesh.0[v as usize])).or_default().push(i);
        }
    }
    let mut vertices: Vec<_> = around
        .into_iter()
        .filter(|(k, _)| !rim.contains(k))
        .collect();
    vertices.sort();
    out.extend(vertices.into_iter().map(|(k, triangles)| Target {
        point: from(k),
        triangles,
    }));
    out
}

/// Unit normal of triangle `i` (zero when degenerate).
fn normal(mesh: &MeshData, i: usize) -> Vec3 {
    let [a, b, c] = mesh.1[i].map(|v| Vec3::from(mesh.0[v as usize]));
    (b - a).cross(c - a).normalize_or_zero()
}

/// For each target, a ray from outside the mesh's bounding sphere (3× its radius from the
/// center) with `t = 1` at the target, along a random direction that crosses every triangle
/// around the target transversally (the same side of each plane to the other, at least 3°
/// from grazing): such a ray passes from one side of the surface to the other there, so it
/// must hit. Rays that would only touch a fold or a ridge are not aimed; targets without
/// such a direction in 64 tries (saddles of a rough scan) are skipped.
pub(crate) fn aimed_rays(mesh: &MeshData, targets: &[Target], seed: u64) -> Vec<[f32; 6]> {
    let center = mesh.0.iter().map(|&p| Vec3::from(p)).sum::<Vec3>() / mesh.0.len() as f32;
    let radius = mesh
        .0
        .iter()
        .map(|&p| Vec3::from(p).distance(center))
        .fold(0.0, f32::max);
    let mut rng = Rng::new(seed, &[]);
    let mut rays = Vec::new();
    for target in targets {
        let normals: Vec<Vec3> = target.triangles.iter().map(|&i| normal(mesh, i)).collect();
        if normals.contains(&Vec3::ZERO) {
            continue;
        }
        for _ in 0..64 {
            let (z, phi) = (
                2.0 * rng.uniform() - 1.0,
                std::f32::consts::TAU * rng.uniform(),
            );
            let r = (1.0 - z * z).max(0.0).sqrt();
            let dir = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            let cos: Vec<f32> = normals.iter().map(|n| n.dot(dir)).collect();
            let transversal = cos.iter().all(|&c| c > 0.05) || cos.iter().all(|&c| c < -0.05);
            if transversal {
                let origin = target.point - 3.0 * radius * dir;
                let d = target.point - origin;
                rays.push([origin.x, origin.y, origin.z, d.x, d.y, d.z]);
                break;
            }
        }
    }
    rays
}

/// A random placement: scales of 0.3 to 2 (each mirrored half the time), any rotation, within
/// ±3 of the origin.
pub(crate) fn random_transform(rng: &mut Rng) -> Transform {
    let mut f = |lo: f32, hi: f32| lo + (hi - lo) * rng.uniform();
    let mut scale = Vec3::new(f(0.3, 2.0), f(0.3, 2.0), f(0.3, 2.0));
    if f(0.0, 1.0) < 0.5 {
        scale.x = -scale.x;
    }
    let rotate = Vec3::new(f(0.0, 360.0), f(0.0, 360.0), f(0.0, 360.0));
    let translate = Vec3::new(f(-3.0, 3.0), f(-3.0, 3.0), f(-3.0, 3.0));
    Transform::from_srt(scale, rotate, translate)
}
