//! Which edges and vertices of each triangle lie on the boundary of the surface, for the
//! counting rule [`EdgeRule::Owned`](super::watertight::EdgeRule::Owned).
//!
//! Inside the surface, a ray through an edge or a vertex is given to one of the triangles
//! that meet there by a simulated displacement of the ray (see `watertight`). That needs a
//! triangle on each side: on an edge that only one triangle has (the border of an open mesh,
//! a lone triangle) the displaced ray may fall outside and the crossing would not be counted,
//! and around a vertex of the border the triangles do not close the circle. So:
//! - a triangle owns its boundary edges (an edge no other triangle has), and
//! - a vertex on a boundary edge is owned by one triangle: the first one added that has that
//!   vertex.
//!
//! Edges and vertices are matched by their exact coordinates, not by index, as the
//! watertight test matches them: two triangles that share corner positions share the edge,
//! whichever geometry or vertex array they come from. Degenerate triangles (zero area, which
//! rays never hit) take no part. The scene makes this on its first counting query (the
//! closest-hit and occlusion queries need none of it).

use glam::DVec3;
use rayon::prelude::*;

use super::Corners;

/// A triangle's part of the surface's boundary: bit `k` (0–2) when its edge `k` (the edge
/// opposite corner `k`: B→C, C→A, A→B) is a boundary edge, bit `3 + c` when its corner `c` is
/// a vertex of the boundary, bit `6 + c` when it is, in addition, the triangle that owns that
/// vertex. Zero for a triangle inside a closed surface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Boundary(u16);

impl Boundary {
    /// True when edge `k` (opposite corner `k`) has no other triangle.
    #[inline]
    pub fn edge(self, k: usize) -> bool {
        self.0 >> k & 1 == 1
    }

    /// `Some(owned)` when corner `c` is a vertex of the boundary (owned by this triangle or
    /// not); `None` inside the surface.
    #[inline]
    pub fn vertex(self, c: usize) -> Option<bool> {
        (self.0 >> (3 + c) & 1 == 1).then_some(self.0 >> (6 + c) & 1 == 1)
    }
}

/// A vertex position as an exact key (`-0` and `0` are one point).
type Key = [u32; 3];

fn key(p: glam::Vec3A) -> Key {
    p.to_array().map(|c| (c + 0.0).to_bits())
}

/// True when the triangle has zero area, exactly: the cross product of its edges in `f64`,
/// where the differences of `f32` coordinates and their products are exact.
fn degenerate(c: &Corners) -> bool {
    let [a, b, c] = c.map(|p| DVec3::new(p.x as f64, p.y as f64, p.z as f64));
    (b - a).cross(c - a) == DVec3::ZERO
}

/// Edges from which the sort runs on the pool.
const PARALLEL_SORT: usize = 1 << 18;

/// The corners of edge `k` of `c` (opposite corner `k`) as exact keys, in order.
fn edge_key(c: &Corners, k: usize) -> (Key, Key) {
    let (p, q) = (key(c[(k + 1) % 3]), key(c[(k + 2) % 3]));
    (p.min(q), p.max(q))
}

/// A 64-bit mix of an edge's keys: sorting these (16-byte entries, one integer compare)
/// costs half what sorting the keys themselves did.
fn edge_hash((p, q): (Key, Key)) -> u64 {
    p.iter().chain(&q).fold(0x9e37_79b9_7f4a_7c15u64, |h, &x| {
        (h ^ x as u64)
            .wrapping_mul(0x0100_0000_01b3)
            .rotate_left(29)
    })
}

/// The [`Boundary`] of each triangle of `tris` (in that order; a vertex of the boundary is
/// owned by its first triangle in this order), sorting the edges on `pool`.
pub(crate) fn boundaries(tris: &[Corners], pool: Option<&rayon::ThreadPool>) -> Vec<Boundary> {
    let proper: Vec<bool> = tris.iter().map(|c| !degenerate(c)).collect();
    // Every edge of every proper triangle as (hash, 3·triangle + edge).
    let mut edges: Vec<(u64, u32)> = (0..tris.len())
        .filter(|&i| proper[i])
        .flat_map(|i| (0..3).map(move |k| (i, k)))
        .map(|(i, k)| (edge_hash(edge_key(&tris[i], k)), (3 * i + k) as u32))
        .collect();
    match pool {
        Some(pool) if edges.len() >= PARALLEL_SORT => pool.install(|| edges.par_sort_unstable()),
        _ => edges.sort_unstable(),
    }
    let exact = |e: u32| edge_key(&tris[e as usize / 3], e as usize % 3);
    let mut out = vec![Boundary::default(); tris.len()];
    // Vertices of the boundary.
    let mut vertices: Vec<Key> = Vec::new();
    let mut alone = |e: u32, key: (Key, Key)| {
        out[e as usize / 3].0 |= 1 << (e % 3);
        vertices.extend([key.0, key.1]);
    };
    for run in edges.chunk_by(|a, b| a.0 == b.0) {
        match run {
            [(_, e)] => alone(*e, exact(*e)),
            // Two triangles of one edge, unless their hashes collide.
            [(_, e), (_, f)] => {
                let (a, b) = (exact(*e), exact(*f));
                if a != b {
                    alone(*e, a);
                    alone(*f, b);
                }
            }
            // Within a longer run (many triangles on one edge: coincident copies), each edge
            // alone with its exact key is on the boundary; sorted by key, in O(k log k) for
            // k edges rather than comparing every pair.
            _ => {
                let mut keyed: Vec<((Key, Key), u32)> =
                    run.iter().map(|&(_, e)| (exact(e), e)).collect();
                keyed.sort_unstable();
                for same in keyed.chunk_by(|a, b| a.0 == b.0) {
                    if let [(key, e)] = same {
                        alone(*e, *key);
                    }
                }
            }
        }
    }
    vertices.sort_unstable();
    vertices.dedup();
    if vertices.is_empty() {
        return out;
    }
    let mut owner: Vec<Option<u32>> = vec![None; vertices.len()];
    for (i, c) in tris.iter().enumerate().filter(|&(i, _)| proper[i]) {
        for (corner, p) in c.iter().enumerate() {
            let Ok(v) = vertices.binary_search(&key(*p)) else {
                continue;
            };
            let first = *owner[v].get_or_insert(i as u32);
            out[i].0 |= 1 << (3 + corner);
            if first == i as u32 {
                out[i].0 |= 1 << (6 + corner);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    fn corners(p: [[f32; 3]; 3]) -> Corners {
        p.map(Vec3A::from)
    }

    #[test]
    fn edges_and_vertices_of_the_border_are_marked() {
        let (a, b, c, d) = (
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        );
        // A lone triangle owns all its edges and corners.
        let lone = boundaries(&[corners([a, b, c])], None);
        assert!((0..3).all(|k| lone[0].edge(k) && lone[0].vertex(k) == Some(true)));
        // A square of two triangles sharing the diagonal a–c (edge 1 of the first, C→A; edge
        // 2 of the second, A→B): the diagonal is inside, its ends are on the border and
        // belong to the first triangle.
        let square = boundaries(&[corners([a, b, c]), corners([a, c, d])], None);
        assert_eq!([0, 1, 2].map(|k| square[0].edge(k)), [true, false, true]);
        assert_eq!([0, 1, 2].map(|k| square[1].edge(k)), [true, true, false]);
        assert_eq!(square[0].vertex(0), Some(true));
        assert_eq!(square[1].vertex(0), Some(false));
        assert_eq!(square[1].vertex(2), Some(true));
        // -0 is 0; a degenerate triangle neither shares nor owns anything.
        let minus = corners([[-0.0, 0.0, 0.0], c, d]);
        let flat = corners([a, b, [2.0, 0.0, 0.0]]);
        let shared = boundaries(&[flat, corners([a, b, c]), minus], None);
        assert_eq!(shared[0], Boundary::default());
        assert!(!shared[1].edge(1) && !shared[2].edge(2));
        assert_eq!(shared[1].vertex(0), Some(true));
        assert_eq!(shared[2].vertex(0), Some(false));
    }

    #[test]
    fn a_closed_surface_has_no_boundary() {
        // A tetrahedron.
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let tris: Vec<Corners> = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]
            .iter()
            .map(|t: &[usize; 3]| corners(t.map(|i| p[i])))
            .collect();
        assert!(boundaries(&tris, None)
            .iter()
            .all(|b| *b == Boundary::default()));
    }

    /// The rule by its definition, comparing every pair: an edge of a proper triangle is on
    /// the boundary when no other proper triangle has it; a corner there is a vertex of the
    /// boundary, owned by the first proper triangle with a corner at that point.
    fn pairwise(tris: &[Corners]) -> Vec<Boundary> {
        let proper: Vec<usize> = (0..tris.len()).filter(|&i| !degenerate(&tris[i])).collect();
        let edges: Vec<(usize, usize)> = proper
            .iter()
            .flat_map(|&i| (0..3).map(move |k| (i, k)))
            .collect();
        let key_of = |&(i, k): &(usize, usize)| edge_key(&tris[i], k);
        let mut out = vec![Boundary::default(); tris.len()];
        let mut on_border = Vec::new();
        for e in &edges {
            if edges.iter().filter(|&f| key_of(f) == key_of(e)).count() == 1 {
                out[e.0].0 |= 1 << e.1;
                on_border.extend([key_of(e).0, key_of(e).1]);
            }
        }
        for &i in &proper {
            for (corner, p) in tris[i].iter().enumerate() {
                if on_border.contains(&key(*p)) {
                    out[i].0 |= 1 << (3 + corner);
                    let first = proper
                        .iter()
                        .find(|&&j| tris[j].iter().any(|q| key(*q) == key(*p)));
                    if first == Some(&i) {
                        out[i].0 |= 1 << (6 + corner);
                    }
                }
            }
        }
        out
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]

        /// Soups on a lattice of 3 × 3 × 3 points (z = 0 as both zeros): many triangles
        /// share each edge, copies and mirrored copies included, and some are degenerate.
        #[test]
        fn the_sorted_rule_is_the_pairwise_rule(
            picks in proptest::collection::vec(proptest::array::uniform3(0usize..27), 1..120),
            copies in proptest::collection::vec(0usize..120, 0..40),
        ) {
            let z = [0.0, -0.0, 1.0];
            let point = |p: usize| Vec3A::new((p % 3) as f32, (p / 3 % 3) as f32, z[p / 9]);
            let mut tris: Vec<Corners> = picks.iter().map(|t| t.map(point)).collect();
            // Copies of some triangles, turned around or not.
            for &c in &copies {
                let t = tris[c % picks.len()];
                tris.push(if c % 2 == 0 { t } else { [t[0], t[2], t[1]] });
            }
            proptest::prop_assert_eq!(boundaries(&tris, None), pairwise(&tris));
        }
    }
}
