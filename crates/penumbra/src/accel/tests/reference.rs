//! The reference build: the straightforward serial binned-SAH build as it was before the
//! build learned to bin in parallel, bin all axes in one pass, skip empty bins and take child
//! bounds from the split (kept verbatim, only renamed). Every optimized build, serial or
//! parallel, must give exactly its tree: the same nodes, bit for bit, and the same primitive
//! order.

use super::*;
use crate::accel::build::node;
use crate::math::Aabb;

#[derive(Clone, Copy)]
struct RefPrim {
    bounds: Aabb,
    centroid: Vec3,
    index: u32,
}

/// The tree the reference build gives for `geometry`.
pub(super) fn reference_build(geometry: &Geometry) -> Bvh {
    let mut prims: Vec<RefPrim> = (0..geometry.len())
        .map(|i| {
            let bounds = geometry
                .corners(i)
                .into_iter()
                .fold(Aabb::EMPTY, Aabb::grow);
            RefPrim {
                bounds,
                centroid: bounds.center(),
                index: i as u32,
            }
        })
        .collect();
    if prims.is_empty() {
        return Bvh::default();
    }
    let mut nodes = vec![node(Aabb::EMPTY, 0, 0)];
    build_into(&mut nodes, 0, &mut prims, 0, 0);
    let prim_ids: Vec<u32> = prims.iter().map(|p| p.index).collect();
    let tris = prim_ids
        .iter()
        .map(|&i| accel(geometry.corners(i as usize)))
        .collect();
    Bvh {
        nodes,
        tris,
        prim_ids,
    }
}

fn bounds_of(prims: &[RefPrim]) -> (Aabb, Aabb) {
    prims.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), p| {
        (b.union(p.bounds), c.grow(p.centroid))
    })
}

/// Builds the subtree over `prims` into `nodes[index]`, appending its descendants.
fn build_into(
    nodes: &mut Vec<BvhNode>,
    index: usize,
    prims: &mut [RefPrim],
    offset: usize,
    depth: usize,
) {
    let (bounds, centroids) = bounds_of(prims);
    let Some(mid) = split(prims, bounds, centroids, depth) else {
        nodes[index] = node(bounds, offset, prims.len());
        return;
    };
    let first = nodes.len();
    nodes[index] = node(bounds, first, 0);
    nodes.push(nodes[index]);
    nodes.push(nodes[index]);
    let (left, right) = prims.split_at_mut(mid);
    build_into(nodes, first, left, offset, depth + 1);
    build_into(nodes, first + 1, right, offset + mid, depth + 1);
}

/// Chooses a split by binned SAH over all three axes and partitions `prims` by it. Returns the
/// size of the left part, or `None` when a leaf is cheaper.
fn split(prims: &mut [RefPrim], bounds: Aabb, centroids: Aabb, depth: usize) -> Option<usize> {
    let n = prims.len();
    // Past MAX_DEPTH (only reached by adversarial inputs, such as triangles spread over
    // hundreds of orders of magnitude) a leaf, however large, keeps traversal in its stack.
    if n <= 2 || depth >= MAX_DEPTH {
        return None;
    }
    let extent = centroids.extent();
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bin)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let bin_of = |p: &RefPrim| bin_index(p, axis, centroids.min[axis], extent[axis]);
        let mut bin_bounds = [Aabb::EMPTY; BINS];
        let mut bin_counts = [0usize; BINS];
        for p in prims.iter() {
            let b = bin_of(p);
            bin_bounds[b] = bin_bounds[b].union(p.bounds);
            bin_counts[b] += 1;
        }
        // Sweep from the right to get the cost of every split plane's right side.
        let mut right_cost = [0.0f32; BINS];
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for b in (1..BINS).rev() {
            acc = acc.union(bin_bounds[b]);
            count += bin_counts[b];
            right_cost[b] = acc.half_area() * count as f32;
        }
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for b in 0..BINS - 1 {
            acc = acc.union(bin_bounds[b]);
            count += bin_counts[b];
            if count == 0 || count == n {
                continue;
            }
            let cost = acc.half_area() * count as f32 + right_cost[b + 1];
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    // SAH with traversal cost 1 and intersection cost 1, relative to the parent's area.
    let leaf_cost = n as f32;
    let area = bounds.half_area().max(f32::MIN_POSITIVE);
    match best {
        Some((cost, axis, bin)) if n > MAX_LEAF || 1.0 + cost / area < leaf_cost => {
            let (min, extent) = (centroids.min[axis], extent[axis]);
            let mid = partition(prims, |p| bin_index(p, axis, min, extent) <= bin);
            Some(mid)
        }
        Some(_) => None,
        // Every centroid coincides: SAH cannot separate them, so split by count to keep
        // leaves small.
        None if n > MAX_LEAF => Some(n / 2),
        None => None,
    }
}

/// The SAH bin of `p`'s centroid along `axis`, for centroids starting at `min` over `extent`.
fn bin_index(p: &RefPrim, axis: usize, min: f32, extent: f32) -> usize {
    (((p.centroid[axis] - min) * (BINS as f32 / extent)) as usize).min(BINS - 1)
}

/// Moves the elements satisfying `pred` to the front; returns how many there are.
fn partition(prims: &mut [RefPrim], pred: impl Fn(&RefPrim) -> bool) -> usize {
    let mut i = 0;
    for j in 0..prims.len() {
        if pred(&prims[j]) {
            prims.swap(i, j);
            i += 1;
        }
    }
    i
}

/// Random numbers in `[-10, 10)` from a fixed seed.
fn uniform(seed: u64) -> impl FnMut() -> f32 {
    let mut state = seed;
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 40) as f32 / (1u64 << 24) as f32) * 20.0 - 10.0
    }
}

/// Serial, parallel and reference builds of `g` give the same tree.
fn assert_matches_reference(g: &Geometry) {
    let reference = reference_build(g);
    let serial = Bvh::build(g);
    assert_same_tree(&serial, &reference);
    let parallel = Bvh::build_parallel(g, pool());
    assert_same_tree(&parallel, &reference);
    parallel.validate(g).unwrap();
}

#[test]
fn large_soups_match_the_reference() {
    // Big enough for the top splits to bin in parallel.
    let mut rnd = uniform(7);
    let small: Vec<_> = (0..300_000)
        .map(|_| {
            let c = [rnd(), rnd(), rnd()];
            [0, 1, 2].map(|_| [0, 1, 2].map(|k| c[k] + rnd() * 0.01))
        })
        .collect();
    assert_matches_reference(&soup(&small));

    // A few large triangles ahead of a dense cluster, as walls ahead of a scanned mesh: the
    // root's split cuts off a handful of triangles, and the rest is still built in parallel.
    let mut walls: Vec<_> = (0..6)
        .map(|_| [0, 1, 2].map(|_| [rnd() * 10.0, rnd() * 10.0, rnd() * 10.0]))
        .collect();
    walls.extend(
        small
            .iter()
            .take(150_000)
            .map(|t| t.map(|p| p.map(|x| x * 0.1))),
    );
    assert_matches_reference(&soup(&walls));

    // Small-integer coordinates: many coinciding centroids, ties between planes, empty bins
    // and axes without extent.
    let lattice: Vec<_> = (0..100_000)
        .map(|_| {
            let c = [rnd(), rnd() * 0.2, 0.0].map(f32::round);
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
                .map(|d| [c[0] + d[0], c[1] + d[1], c[2] + d[2]])
        })
        .collect();
    assert_matches_reference(&soup(&lattice));
}

/// The scene of the 1M-triangle mesh the build is benchmarked on, when it is on this machine
/// (`PENUMBRA_BLOB_SCENE`, else `../shared/embree-bench/` beside the repository, whose
/// `setup.sh` generates the mesh beside the scene); skipped, saying which file is missing,
/// when either is.
#[test]
fn blob_mesh_matches_the_reference() {
    let path = std::env::var_os("PENUMBRA_BLOB_SCENE").map_or_else(
        || {
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../../shared/embree-bench/scenes/cornell_blob1m.toml")
        },
        std::path::PathBuf::from,
    );
    let mesh = path.with_file_name("meshes/blob_1m.obj");
    if let Some(missing) = [&path, &mesh].into_iter().find(|p| !p.is_file()) {
        eprintln!(
            "blob_mesh_matches_the_reference skipped: no {} (run ../shared/embree-bench/setup.sh, \
             or set PENUMBRA_BLOB_SCENE)",
            missing.display()
        );
        return;
    }
    let scene = crate::SceneFile::load(&path).unwrap().build(2).unwrap();
    let g = scene.world.geometry();
    assert!(g.len() > 1_000_000);
    let reference = reference_build(g);
    assert_same_tree(scene.world.accel().flat(), &reference);
    assert_same_tree(&Bvh::build(g), &reference);
}
