//! Many coincident triangles: the counting queries' border (which edges no other triangle
//! has) is found by sorting, so that 10⁵ copies of one triangle (10⁵ triangles on each edge)
//! are counted and listed at once; every copy is a crossing.

use super::*;

/// `n` copies of one triangle, as one geometry, and rays straight through its interior,
/// through the midpoint of an edge and through a vertex.
fn copies(n: u32) -> (RaycastingScene, Vec<[f32; 6]>) {
    let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let triangles = vec![[0, 1, 2]; n as usize];
    let mut scene = RaycastingScene::new();
    scene.add_triangles(&vertices, &triangles).unwrap();
    let rays = vec![
        [0.25, 0.25, 1.0, 0.0, 0.0, -1.0],
        [0.2, 0.3, -2.0, 0.0, 0.0, 1.0],
        [0.5, 0.0, 1.0, 0.0, 0.0, -1.0],
        [0.0, 0.0, 1.0, 0.0, 0.0, -1.0],
    ];
    (scene, rays)
}

#[test]
fn a_hundred_thousand_copies_of_a_triangle_are_counted_at_once() {
    // Before the border was found by sorting, 10⁴ copies took seconds (each edge compared
    // with every other on it) and 10⁵ never finished.
    let n = 100_000;
    let (scene, rays) = copies(n);
    let options = QueryOptions::default();
    // Every copy's edges are shared (by the other copies), so none is on the border: a ray
    // through the interior crosses every copy once, a ray through an edge or vertex crosses
    // the copies the edge rule gives it to, the same on every copy.
    let counts = scene.count_intersections(&rays, &options).unwrap();
    assert_eq!(counts[..2], [n as i32; 2]);
    assert!(
        counts[2..].iter().all(|&c| c == 0 || c == n as i32),
        "{counts:?}"
    );
    let listed = scene.list_intersections(&rays[..1], &options).unwrap();
    assert_eq!(listed.ray_splits, [0, n]);
    // Equal `t`: listed by primitive id.
    assert!(listed.primitive_ids.iter().copied().eq(0..n));
    assert!(listed.t_hit.iter().all(|&t| t == 1.0));
}
