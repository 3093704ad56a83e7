//! Cut-outs in every query of the engine: random quads, some with a checkerboard alpha (a
//! checker texture's luminance, or an RGBA image's alpha plane), some cut away entirely,
//! some opaque, placed by random transforms. A brute-force reference that tests every
//! triangle and applies the alpha test must agree with the closest-hit and any-hit queries
//! bit for bit; every batched query (camera fans, shadow fans, bundles of segments, shafts)
//! must agree with the single-ray ones on every SIMD path; instanced meshes (a cut-out
//! triangle and an opaque one in each) must answer as their copies do, up to a hair (a ray
//! through an edge or a texel's border may go either way in two roundings: see `copies`).

use std::sync::Arc;

use glam::{Vec2, Vec3};
use penumbra::bench::{Pairs, Segments};
use penumbra::{
    intersect_triangle, supported_paths, Cutout, Filter, Image, ImageTexture, Material, Mesh, Ray,
    Texture, TextureKind, Transform, World, WorldBuilder, Wrap,
};
use proptest::prelude::*;

mod copies;
use copies::{hit_near, ids, occluded_near};

/// Material kinds: opaque, checker cut-out, image-alpha cut-out, cut away everywhere.
const KINDS: u32 = 4;

/// One quad: corner, edges, placement, and the material kind of each of its two triangles.
type Quad = (Vec3, Vec3, Vec3, Transform, [u32; 2]);

fn arb_quad() -> impl Strategy<Value = Quad> {
    let vec = |r: f32| prop::array::uniform3(-r..r).prop_map(Vec3::from);
    (
        vec(1.0),
        vec(3.0),
        vec(3.0),
        prop::array::uniform3(-180.0f32..180.0),
        vec(4.0),
        prop::array::uniform2(0..KINDS),
    )
        .prop_map(|(corner, u, v, rotate, translate, kinds)| {
            let t = Transform::from_srt(Vec3::ONE, Vec3::from(rotate), translate);
            (corner, u, v, t, kinds)
        })
}

fn arb_rays() -> impl Strategy<Value = Vec<Ray>> {
    let point = || prop::array::uniform3(-9.0f32..9.0).prop_map(Vec3::from);
    prop::collection::vec((point(), point()), 1..48).prop_map(|v| {
        v.into_iter()
            .map(|(o, target)| Ray::new(o, target - o))
            .filter(|r| r.direction.length() > 1e-2)
            .collect()
    })
}

/// The quad's mesh in object space: triangle 0 in slot 0, triangle 1 in slot 1.
fn mesh((corner, u, v, ..): &Quad) -> Mesh {
    Mesh {
        material_slots: vec![0, 1],
        ..penumbra::shapes::quad(*corner, *u, *v)
    }
}

/// The materials of every kind (indices `first + kind`), with their textures.
fn add_materials(b: &mut WorldBuilder) -> u32 {
    let checker = b.add_texture(Texture {
        kind: TextureKind::Checker {
            even: Vec3::ONE,
            odd: Vec3::ZERO,
            checks: 4.0,
        },
        uv_scale: Vec2::ONE,
        uv_offset: Vec2::ZERO,
    });
    let rgba = [[0.2, 0.4, 0.6, 1.0], [0.1, 0.1, 0.1, 0.0]];
    let image = Image::from_rgba(2, 2, &[rgba[0], rgba[1], rgba[1], rgba[0]], true).unwrap();
    let alpha = b.add_texture(Texture {
        kind: TextureKind::Image(ImageTexture {
            image: Arc::new(image),
            filter: Filter::Nearest,
            wrap: Wrap::Repeat,
        }),
        uv_scale: Vec2::splat(3.0),
        uv_offset: Vec2::ZERO,
    });
    let cutouts = [
        None,
        Some(Cutout::with_texture(checker, 0.5)),
        Some(Cutout::with_texture(alpha, 0.5)),
        Some(Cutout {
            texture: None,
            factor: 0.2,
            cutoff: 0.5,
        }),
    ];
    let mut first = None;
    for cutout in cutouts {
        let m = Material {
            diffuse: Vec3::new(0.7, 0.3, 0.2),
            cutout,
            ..Material::default()
        };
        let id = b.add_material(m).unwrap();
        first.get_or_insert(id);
    }
    first.unwrap()
}

/// The world of `quads`, each copied into the world or placed as an instance.
fn world(quads: &[Quad], instanced: bool) -> World {
    let mut b = WorldBuilder::new();
    let first = add_materials(&mut b);
    for q in quads {
        let materials = q.4.map(|k| first + k);
        if instanced {
            let id = b.add_shared_mesh(mesh(q)).unwrap();
            b.add_instance(id, &q.3, &materials).unwrap();
        } else {
            b.add_mesh(&mesh(q), &q.3, &materials).unwrap();
        }
    }
    b.build(1)
}

/// True when the hit at barycentrics `(b1, b2)` of `world`'s triangle `i` is kept: its
/// material's alpha test at the uv the barycentrics interpolate.
fn kept(world: &World, i: usize, b1: f32, b2: f32) -> bool {
    let g = world.geometry();
    let t = &g.triangles[i];
    let uv = t.vertices.map(|v| g.uvs[v as usize]);
    let uv = (1.0 - b1 - b2) * uv[0] + b1 * uv[1] + b2 * uv[2];
    let cutout = world.materials()[t.material as usize].cutout;
    cutout.is_none_or(|c| {
        let texture = c.texture.map(|k| &world.textures()[k as usize]);
        c.keeps(texture, uv)
    })
}

/// The closest kept hit by testing every triangle of a world without instances: the
/// smallest `t`, then the smallest triangle index.
fn closest_brute_force(world: &World, ray: &Ray, t_min: f32, t_max: f32) -> Option<(f32, u32)> {
    let g = world.geometry();
    let mut best: Option<(f32, u32)> = None;
    for i in 0..g.len() {
        let [a, b, c] = g.corners(i);
        let Some(h) = intersect_triangle(ray.origin, ray.direction, a, b - a, c - a, t_min, t_max)
        else {
            continue;
        };
        if kept(world, i, h.b1, h.b2) && best.is_none_or(|(t, _)| h.t < t) {
            best = Some((h.t, i as u32));
        }
    }
    best
}

/// True when a kept hit of any triangle meets the ray with `t` in `(t_min, t_max)`.
fn occluded_brute_force(world: &World, ray: &Ray, t_min: f32, t_max: f32) -> bool {
    let g = world.geometry();
    (0..g.len()).any(|i| {
        let [a, b, c] = g.corners(i);
        intersect_triangle(ray.origin, ray.direction, a, b - a, c - a, t_min, t_max)
            .is_some_and(|h| kept(world, i, h.b1, h.b2))
    })
}

/// Checks every batched query of `world` against `single`, a world whose single-ray queries
/// give the same answers bit for bit (the same world, or one built where it was moved).
fn batches_agree(world: &World, single: &World, rays: &[Ray]) -> Result<(), TestCaseError> {
    let origin = rays[0].origin;
    let dirs: Vec<Vec3> = rays.iter().map(|r| r.direction).collect();
    let ends: Vec<Vec3> = rays.iter().map(|r| r.origin + r.direction).collect();
    let occluded = |o: Vec3, e: Vec3| single.accel().occluded(&Ray::new(o, e - o), 0.0, 1.0);
    let expected_from: Vec<bool> = ends.iter().map(|&e| occluded(origin, e)).collect();
    let axes = |p: &[Vec3]| [0, 1, 2].map(|a| p.iter().map(|v| v[a]).collect::<Vec<f32>>());
    let starts: Vec<Vec3> = rays.iter().map(|r| r.origin).collect();
    let (o, e) = (axes(&starts), axes(&ends));
    let expected_segments: Vec<bool> = rays
        .iter()
        .map(|r| occluded(r.origin, r.origin + r.direction))
        .collect();
    let few = &ends[..ends.len().min(4)];
    let f = axes(few);
    let expected_pairs: Vec<bool> = few
        .iter()
        .flat_map(|&end| starts.iter().map(move |&start| (start, end)))
        .map(|(start, end)| occluded(start, end))
        .collect();
    for path in supported_paths() {
        let mut hits = vec![None; dirs.len()];
        world
            .accel()
            .intersect_from_on(path, origin, &dirs, 0.0, f32::INFINITY, &mut hits);
        for (hit, &dir) in hits.into_iter().zip(&dirs) {
            let expected = single.intersect(&Ray::new(origin, dir), 0.0, f32::INFINITY);
            let (a, b) = (
                hit.map(|h| ids(world, &h)),
                expected.map(|h| ids(single, &h)),
            );
            prop_assert_eq!(a, b, "{:?}", path);
        }
        let mut blocked = vec![false; ends.len()];
        world
            .accel()
            .occlude_from_on(path, origin, &ends, 1.0, &mut blocked);
        prop_assert_eq!(&blocked, &expected_from, "fan {:?}", path);
        let segments = Segments {
            origin: [&o[0], &o[1], &o[2]],
            end: [&e[0], &e[1], &e[2]],
        };
        let mut blocked = vec![false; rays.len()];
        world
            .accel()
            .occlude_segments_on(path, segments, 1.0, &mut blocked);
        prop_assert_eq!(&blocked, &expected_segments, "bundle {:?}", path);
        let pairs = Pairs {
            origins: [&o[0], &o[1], &o[2]],
            ends: [&f[0], &f[1], &f[2]],
        };
        let mut blocked = vec![false; expected_pairs.len()];
        world
            .accel()
            .occlude_pairs_on(path, pairs, 1.0, &mut blocked);
        prop_assert_eq!(&blocked, &expected_pairs, "shaft {:?}", path);
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn every_query_passes_through_cut_out_texels(
        quads in prop::collection::vec(arb_quad(), 1..12),
        rays in arb_rays(),
    ) {
        let flat = world(&quads, false);
        prop_assert!(flat.accel().has_cutouts() == quads.iter().any(|q| q.4.iter().any(|&k| k > 0)));
        prop_assert!(flat.accel().validate(flat.geometry()).is_ok());
        for ray in &rays {
            let hit = flat.intersect(ray, 0.0, f32::INFINITY).map(|h| (h.t, h.triangle));
            prop_assert_eq!(hit, closest_brute_force(&flat, ray, 0.0, f32::INFINITY));
            for t_max in [0.3f32, 1.0] {
                let expected = occluded_brute_force(&flat, ray, 0.0, t_max);
                prop_assert_eq!(flat.accel().occluded(ray, 0.0, t_max), expected);
            }
        }
        batches_agree(&flat, &flat, &rays)?;
    }

    #[test]
    fn instances_with_cut_out_triangles_answer_as_their_copies(
        quads in prop::collection::vec(arb_quad(), 1..12),
        rays in arb_rays(),
    ) {
        let (inst, flat) = (world(&quads, true), world(&quads, false));
        for ray in &rays {
            let a = inst.intersect(ray, 0.0, f32::INFINITY);
            let b = flat.intersect(ray, 0.0, f32::INFINITY);
            let found = a.map(|h| ids(&inst, &h));
            if found != b.map(|h| ids(&flat, &h)) {
                prop_assert!(hit_near(&flat, ray, found), "hit {:?} vs {:?}", a, b);
            } else if let (Some(a), Some(b)) = (a, b) {
                // Compared off the surface: a grazing ray's t is only as exact as 1 / sin θ.
                let across = flat.surface(&b).geometric_normal.normalize().dot(ray.direction).abs();
                let scale = ray.origin.length().max(1.0) + b.t * ray.direction.length();
                prop_assert!((a.t - b.t).abs() * across <= 1e-5 * scale, "t {} vs {}", a.t, b.t);
            }
            for t_max in [0.3f32, 1.0] {
                let blocked = inst.accel().occluded(ray, 0.0, t_max);
                prop_assert!(occluded_near(&flat, ray.origin, ray.origin + ray.direction * t_max, blocked));
            }
        }
        // Batches answer as the instanced world's own single rays, bit for bit.
        batches_agree(&inst, &inst, &rays)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    /// Instances moved after the build (cut-out ones among them) answer as instances built
    /// where they were moved to, bit for bit.
    #[test]
    fn moved_instances_answer_as_instances_built_there(
        quads in prop::collection::vec(arb_quad(), 1..12),
        to in prop::collection::vec(arb_quad(), 12),
        rays in arb_rays(),
    ) {
        let mut moved = world(&quads, true);
        let moves: Vec<_> = (0..quads.len()).step_by(2).map(|i| (i, to[i].3)).collect();
        moved.set_transforms(&moves).unwrap();
        let mut there = quads.clone();
        for &(i, t) in &moves {
            there[i].3 = t;
        }
        let fresh = world(&there, true);
        for ray in &rays {
            let a = moved.intersect(ray, 0.0, f32::INFINITY);
            prop_assert_eq!(a, fresh.intersect(ray, 0.0, f32::INFINITY));
            for t_max in [0.3f32, 1.0] {
                prop_assert_eq!(moved.accel().occluded(ray, 0.0, t_max), fresh.accel().occluded(ray, 0.0, t_max));
            }
        }
        batches_agree(&moved, &fresh, &rays)?;
    }
}

#[test]
fn a_world_without_cut_out_materials_has_no_cut_out_levels() {
    let quads = [(Vec3::ZERO, Vec3::X, Vec3::Y, Transform::IDENTITY, [0, 0])];
    assert!(!world(&quads, false).accel().has_cutouts());
    // A cut-out that keeps everything is built as an opaque surface.
    let mut b = WorldBuilder::new();
    let keep_all = Material {
        cutout: Some(Cutout::default()),
        ..Material::default()
    };
    let m = b.add_material(keep_all).unwrap();
    b.add_mesh(&mesh(&quads[0]), &Transform::IDENTITY, &[m])
        .unwrap();
    assert!(!b.build(1).accel().has_cutouts());
}

/// Three unit squares over `[0, 1]²` facing up: at z = 2 (the world's own) a 2×2 checker
/// cut-out kept on its even cells, at z = 1 (an instance) the inverse checker, at z = 0 an
/// opaque floor.
fn stacked() -> World {
    let mut b = WorldBuilder::new();
    let checker = |even: f32| Texture {
        kind: TextureKind::Checker {
            even: Vec3::splat(even),
            odd: Vec3::splat(1.0 - even),
            checks: 2.0,
        },
        uv_scale: Vec2::ONE,
        uv_offset: Vec2::ZERO,
    };
    let mut cut = |even: f32| {
        let t = b.add_texture(checker(even));
        let m = Material {
            cutout: Some(Cutout::with_texture(t, 0.5)),
            ..Material::default()
        };
        b.add_material(m).unwrap()
    };
    let (top, middle) = (cut(1.0), cut(0.0));
    let square = |z: f32| penumbra::shapes::quad(Vec3::new(0.0, 0.0, z), Vec3::X, Vec3::Y);
    b.add_mesh(&square(2.0), &Transform::IDENTITY, &[top])
        .unwrap();
    let shared = b.add_shared_mesh(square(0.0)).unwrap();
    let up = Transform::from_srt(Vec3::ONE, Vec3::ZERO, Vec3::Z);
    b.add_instance(shared, &up, &[middle]).unwrap();
    b.add_mesh(&square(0.0), &Transform::IDENTITY, &[0])
        .unwrap();
    b.build(1)
}

/// Points inside each cell of the 2×2 checker, away from its borders, and whether the top
/// square keeps them (its even cells).
fn cell_points() -> Vec<(f32, f32, bool)> {
    let mut points = Vec::new();
    for (cx, cy) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
        for (fx, fy) in [(0.1, 0.2), (0.5, 0.5), (0.85, 0.3), (0.25, 0.9)] {
            let (x, y) = (0.5 * (cx as f32 + fx), 0.5 * (cy as f32 + fy));
            points.push((x, y, (cx + cy) % 2 == 0));
        }
    }
    points
}

#[test]
fn ray_casting_from_a_world_skips_cut_out_texels_in_every_query() {
    use penumbra::{QueryOptions, RaycastingScene};
    let world = stacked();
    let scene = RaycastingScene::from_world(&world).unwrap();
    let options = QueryOptions::default();
    let points = cell_points();
    let rays: Vec<[f32; 6]> = points
        .iter()
        .map(|&(x, y, _)| [x, y, 5.0, 0.0, 0.0, -1.0])
        .collect();
    let cast = scene.cast_rays(&rays, &options).unwrap();
    let occluded = scene.test_occlusions(&rays, 0.0, 3.5, &options).unwrap();
    let counts = scene.count_intersections(&rays, &options).unwrap();
    let listed = scene.list_intersections(&rays, &options).unwrap();
    for (i, &(x, y, top)) in points.iter().enumerate() {
        // The top square where it is kept, else the middle one (kept exactly there).
        let (object, t) = if top { (0, 3.0) } else { (1, 4.0) };
        assert_eq!(
            (cast.geometry_ids[i], cast.t_hit[i]),
            (object, t),
            "at {x}, {y}"
        );
        assert_eq!(occluded[i], top, "at {x}, {y}");
        // One of the two cut-out squares, and the floor.
        assert_eq!(counts[i], 2, "at {x}, {y}");
        let hits = listed.ray_splits[i] as usize..listed.ray_splits[i + 1] as usize;
        assert_eq!(listed.geometry_ids[hits], [object, 2], "at {x}, {y}");
        // The renderer's engine agrees.
        let ray = Ray::new(Vec3::new(x, y, 5.0), -Vec3::Z);
        let hit = world.intersect(&ray, 0.0, f32::INFINITY).unwrap();
        assert_eq!((world.surface(&hit).object, hit.t), (object, t));
    }
    // A copy of the top square keeps its cut-out.
    let mut scene = scene;
    let lifted = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 10.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let copy = scene.add_instance(0, &lifted).unwrap();
    let from_above: Vec<[f32; 6]> = points
        .iter()
        .map(|&(x, y, _)| [x, y, 20.0, 0.0, 0.0, -1.0])
        .collect();
    let cast = scene.cast_rays(&from_above, &options).unwrap();
    for (i, &(_, _, top)) in points.iter().enumerate() {
        let (object, t) = if top { (copy, 8.0) } else { (1, 19.0) };
        assert_eq!(cast.geometry_ids[i], object);
        assert!((cast.t_hit[i] - t).abs() < 1e-5 * t, "t {}", cast.t_hit[i]);
    }
}

/// The pixel of a 1×1 render looking from above at `target` on a white floor lit by a point
/// light at (−4, 0, 5), with `extra` scene text (materials and objects) added.
fn probe(target: Vec3, extra: &str) -> [u32; 3] {
    use penumbra::{render, RenderOptions, SceneFile, SceneFormat};
    let text = format!(
        "[film]\nwidth = 1\nheight = 1\n\n[camera]\nposition = [4, 0, 10]\n\
         look_at = [{}, {}, 0]\nup = [0, 1, 0]\nfov = 30\n\n[render]\nsampler = \"center\"\n\n\
         [[lights]]\ntype = \"point\"\nposition = [-4, 0, 5]\n\n\
         [materials.white]\ndiffuse = 1\n\n\
         [[objects]]\ntype = \"quad\"\nmaterial = \"white\"\ncorner = [-20, -20, 0]\n\
         u = [40, 0, 0]\nv = [0, 40, 0]\n\n{extra}",
        target.x, target.y
    );
    let scene = SceneFile::from_str(
        &text,
        SceneFormat::Toml,
        "probe.toml",
        std::path::Path::new("."),
    )
    .and_then(|f| f.build(1))
    .unwrap_or_else(|e| panic!("{e}\n{text}"));
    let (film, _) = render(&scene.world, &scene.settings, &RenderOptions::default()).unwrap();
    film.get(0, 0).to_array().map(f32::to_bits)
}

#[test]
fn a_cut_out_card_casts_a_shadow_with_its_holes() {
    // A card over [-1, 1]² at z = 2.5, halfway between the light and the floor: the shadow
    // ray from floor point F meets it at P = (F + light) / 2, so its shadow spans x in [2, 6].
    // Its alpha is a 4×4 checker (even cells kept); the camera sees the floor beside it.
    let card = |material: &str| {
        format!(
            "[[objects]]\ntype = \"quad\"\nmaterial = \"{material}\"\ncorner = [-1, -1, 2.5]\n\
             u = [2, 0, 0]\nv = [0, 2, 0]\n\n"
        )
    };
    let cut = "[textures.holes]\ntype = \"checker\"\nchecks = 4\n\n\
               [materials.leaf]\nalpha_texture = \"holes\"\nalpha_cutoff = 0.5\n\n";
    let light = Vec3::new(-4.0, 0.0, 5.0);
    let (mut lit, mut shadowed) = (0, 0);
    for i in 0..6 {
        for j in 0..6 {
            // Points inside the shadow, away from the cells' borders (cells 0.125 of uv wide).
            let (s, t) = (0.04 + 0.17 * i as f32, 0.06 + 0.165 * j as f32);
            let cell = (s * 4.0).floor() + (t * 4.0).floor();
            let edge = |x: f32| ((x * 4.0) - (x * 4.0).round()).abs() < 0.05;
            if edge(s) || edge(t) {
                continue;
            }
            let p = Vec3::new(2.0 * s - 1.0, 2.0 * t - 1.0, 2.5);
            let floor = 2.0 * p - light;
            let floor = Vec3::new(floor.x, floor.y, 0.0);
            let got = probe(floor, &format!("{cut}{}", card("leaf")));
            let hole = cell.rem_euclid(2.0) == 1.0;
            let expected = if hole {
                lit += 1;
                probe(floor, "")
            } else {
                shadowed += 1;
                probe(floor, &format!("{cut}[materials.card]\n\n{}", card("card")))
            };
            assert_eq!(got, expected, "floor point {floor} (card uv {s}, {t})");
        }
    }
    assert!(
        lit >= 8 && shadowed >= 8,
        "{lit} lit and {shadowed} shadowed points"
    );
    // The lit and the shadowed floor differ, so the comparison means something.
    let f = Vec3::new(4.0, 0.0, 0.0);
    assert_ne!(probe(f, ""), probe(f, &card("white")));
}
