//! Two-level instancing against copies: random meshes placed by random instances (nested
//! transforms composed, mirrored, scaled non-uniformly) must answer every query as the same
//! scene with every instance copied into the world does: the same hit, `t` within 1e-5 of
//! the scene's scale off the surface, the same ids, uvs, vertex colours and normals; the same
//! occlusion for single rays, shared-origin packets, bundles of segments and shafts, on every
//! SIMD path. Batches answer as one-ray queries bit for bit; the copies answer as instances up
//! to a hair (a ray through an edge may go either way in two roundings: see `copies`).

use glam::{Vec2, Vec3};
use penumbra::bench::{Pairs, Segments};
use penumbra::{supported_paths, Hit, Material, Mesh, Ray, Transform, World, WorldBuilder};
use proptest::prelude::*;

mod copies;
use copies::{hit_near, ids, occluded_near, occlusions_near};

/// A small random mesh near the origin, with uvs and (sometimes) vertex normals and colours.
fn arb_mesh() -> impl Strategy<Value = Mesh> {
    (
        prop::collection::vec(prop::array::uniform3(-1.0f32..1.0), 3..30),
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(|(points, smooth, colored)| {
            let positions: Vec<Vec3> = points.into_iter().map(Vec3::from).collect();
            let n = positions.len() as u32;
            let indices = (0..n / 3).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
            let uvs = positions.iter().map(|p| Vec2::new(p.x, p.y)).collect();
            let normals = if smooth {
                positions
                    .iter()
                    .map(|p| (*p + Vec3::Z).normalize_or(Vec3::Z))
                    .collect()
            } else {
                Vec::new()
            };
            let colors = match colored {
                true => positions.iter().map(|p| p.abs().min(Vec3::ONE)).collect(),
                false => Vec::new(),
            };
            Mesh {
                material_slots: (0..n / 3).map(|t| t % 2).collect(),
                positions,
                normals,
                uvs,
                colors,
                indices,
            }
        })
}

/// One placement: non-uniform scale (a negative factor mirrors), rotation and translation.
fn arb_transform() -> impl Strategy<Value = Transform> {
    (
        prop::array::uniform3((0.3f32..3.0, any::<bool>())),
        prop::array::uniform3(-180.0f32..180.0),
        prop::array::uniform3(-6.0f32..6.0),
    )
        .prop_map(|(s, r, t)| {
            let scale = Vec3::from(s.map(|(v, mirror)| if mirror { -v } else { v }));
            Transform::from_srt(scale, Vec3::from(r), Vec3::from(t))
        })
}

/// A node path of one to three placements composed, as a scene graph nests them.
fn arb_nested() -> impl Strategy<Value = Transform> {
    prop::collection::vec(arb_transform(), 1..4).prop_map(|chain| {
        chain
            .into_iter()
            .reduce(|outer, inner| outer.then_after(inner))
            .unwrap()
    })
}

#[derive(Debug, Clone)]
struct Case {
    own: Vec<Mesh>,
    meshes: Vec<Mesh>,
    instances: Vec<(usize, Transform, u32)>,
}

fn arb_case() -> impl Strategy<Value = Case> {
    (
        prop::collection::vec(arb_mesh(), 0..3),
        prop::collection::vec(arb_mesh(), 1..4),
    )
        .prop_flat_map(|(own, meshes)| {
            let n = meshes.len();
            let instances = prop::collection::vec((0..n, arb_nested(), 1u32..3), 1..24);
            (Just(own), Just(meshes), instances)
        })
        .prop_map(|(own, meshes, instances)| Case {
            own,
            meshes,
            instances,
        })
}

/// The scene with its instances placed (`instanced`) or copied.
fn world(case: &Case, instanced: bool) -> World {
    let mut b = WorldBuilder::new();
    let red = b.add_material(Material::default()).unwrap();
    let green = b.add_material(Material::default()).unwrap();
    for mesh in &case.own {
        b.add_mesh(mesh, &Transform::IDENTITY, &[red]).unwrap();
    }
    let ids: Vec<u32> = case
        .meshes
        .iter()
        .map(|m| b.add_shared_mesh(m.clone()).unwrap())
        .collect();
    for (mesh, transform, material) in &case.instances {
        let materials = [*material, green];
        if instanced {
            b.add_instance(ids[*mesh], transform, &materials).unwrap();
        } else {
            b.add_mesh(&case.meshes[*mesh], transform, &materials)
                .unwrap();
        }
    }
    b.build(1)
}

fn arb_rays() -> impl Strategy<Value = Vec<Ray>> {
    let point = || prop::array::uniform3(-9.0f32..9.0).prop_map(Vec3::from);
    prop::collection::vec((point(), point()), 1..64).prop_map(|v| {
        v.into_iter()
            .map(|(o, target)| Ray::new(o, target - o))
            .filter(|r| r.direction.length() > 1e-2)
            .collect()
    })
}

/// The same hit in both worlds, or (for a ray through an edge) the hit the copies give the
/// ray moved by a hair. A ray that grazes a triangle at angle θ to its plane finds its point
/// along the ray only to 1 / sin θ times float precision, so `t` is compared off the surface
/// and what is interpolated at the point (uv, colour, shading normal, position) within
/// tolerances that grow by 1 / sin θ (up to 1000×).
fn same_hit(
    ray: &Ray,
    a: (&World, Option<Hit>),
    b: (&World, Option<Hit>),
) -> Result<(), TestCaseError> {
    let (wa, ha) = a;
    let (wb, hb) = b;
    let found = ha.map(|x| ids(wa, &x));
    if found != hb.map(|y| ids(wb, &y)) {
        prop_assert!(hit_near(wb, ray, found), "hit {:?} vs {:?}", ha, hb);
        return Ok(());
    }
    match (ha, hb) {
        (Some(x), Some(y)) => {
            let (sa, sb) = (wa.surface(&x), wb.surface(&y));
            // How far apart the two answers lie off the surface, against the scene's scale.
            let across = sb.geometric_normal.normalize().dot(ray.direction).abs();
            let scale = sb.position.length().max(ray.origin.length()).max(1.0);
            let grazing = (ray.direction.length() / across).min(1e3);
            prop_assert!(
                (x.t - y.t).abs() * across <= 1e-5 * scale,
                "t {} vs {} (1 / sin θ {})",
                x.t,
                y.t,
                grazing
            );
            prop_assert_eq!(sa.material, sb.material);
            let near = |p: f32, tolerance: f32| p < tolerance * grazing;
            prop_assert!(
                near((sa.uv - sb.uv).length(), 1e-4),
                "uv {} vs {}",
                sa.uv,
                sb.uv
            );
            prop_assert!(
                near((sa.color - sb.color).length(), 1e-4),
                "colour {} vs {}",
                sa.color,
                sb.color
            );
            prop_assert!((sa.geometric_normal - sb.geometric_normal).length() < 1e-3);
            prop_assert!(near((sa.shading_normal - sb.shading_normal).length(), 1e-3));
            prop_assert!(near((sa.position - sb.position).length(), 1e-4 * scale));
            Ok(())
        }
        _ => Ok(()),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn instanced_scenes_answer_as_their_copies(case in arb_case(), rays in arb_rays()) {
        let (inst, flat) = (world(&case, true), world(&case, false));
        prop_assert_eq!(inst.stats().triangles, flat.stats().triangles);
        prop_assert_eq!(inst.stats().instances, case.instances.len());
        for ray in &rays {
            let (a, b) = (inst.intersect(ray, 0.0, f32::INFINITY), flat.intersect(ray, 0.0, f32::INFINITY));
            same_hit(ray, (&inst, a), (&flat, b))?;
            for t_max in [0.3f32, 1.0] {
                let end = ray.origin + ray.direction * t_max;
                let blocked = inst.accel().occluded(ray, 0.0, t_max);
                prop_assert!(occluded_near(&flat, ray.origin, end, blocked), "{:?} to {}", ray, t_max);
            }
        }
        // Batched queries from one origin, between the rays' origins and their ends: each the
        // instanced world's one-ray answer, bit for bit, and that one the copies' up to a hair.
        let origin = rays[0].origin;
        let dirs: Vec<Vec3> = rays.iter().map(|r| r.direction).collect();
        let ends: Vec<Vec3> = rays.iter().map(|r| r.origin + r.direction).collect();
        let starts: Vec<Vec3> = rays.iter().map(|r| r.origin).collect();
        let few = &ends[..ends.len().min(4)];
        let fan: Vec<(Vec3, Vec3)> = ends.iter().map(|&e| (origin, e)).collect();
        let bundle: Vec<(Vec3, Vec3)> = starts.iter().copied().zip(ends.iter().copied()).collect();
        let shaft: Vec<(Vec3, Vec3)> = few.iter().flat_map(|&e| starts.iter().map(move |&s| (s, e))).collect();
        let occluded = |q: &[(Vec3, Vec3)]| -> Vec<bool> {
            q.iter().map(|&(s, e)| inst.accel().occluded(&Ray::new(s, e - s), 0.0, 1.0)).collect()
        };
        let (expected_from, expected_segments, expected_pairs) = (occluded(&fan), occluded(&bundle), occluded(&shaft));
        for (q, blocked) in [(&fan, &expected_from), (&bundle, &expected_segments), (&shaft, &expected_pairs)] {
            occlusions_near(&flat, q.iter().copied(), blocked).map_err(TestCaseError::fail)?;
        }
        let axes = |p: &[Vec3]| [0, 1, 2].map(|a| p.iter().map(|v| v[a]).collect::<Vec<f32>>());
        let (o, e, f) = (axes(&starts), axes(&ends), axes(few));
        for path in supported_paths() {
            let mut a = vec![None; dirs.len()];
            let mut b = vec![None; dirs.len()];
            inst.accel().intersect_from_on(path, origin, &dirs, 0.0, f32::INFINITY, &mut a);
            flat.accel().intersect_from_on(path, origin, &dirs, 0.0, f32::INFINITY, &mut b);
            for ((x, y), &dir) in a.into_iter().zip(b).zip(&dirs) {
                // The packet's answer is the one-ray query's, bit for bit.
                let ray = Ray::new(origin, dir);
                prop_assert_eq!(x, inst.intersect(&ray, 0.0, f32::INFINITY));
                prop_assert_eq!(y, flat.intersect(&ray, 0.0, f32::INFINITY));
                same_hit(&ray, (&inst, x), (&flat, y))?;
            }
            let mut blocked = vec![false; ends.len()];
            inst.accel().occlude_from_on(path, origin, &ends, 1.0, &mut blocked);
            prop_assert_eq!(&blocked, &expected_from, "{:?}", path);
            let segments = Segments { origin: [&o[0], &o[1], &o[2]], end: [&e[0], &e[1], &e[2]] };
            let mut blocked = vec![false; rays.len()];
            inst.accel().occlude_segments_on(path, segments, 1.0, &mut blocked);
            prop_assert_eq!(&blocked, &expected_segments, "{:?}", path);
            let pairs = Pairs { origins: [&o[0], &o[1], &o[2]], ends: [&f[0], &f[1], &f[2]] };
            let mut blocked = vec![false; expected_pairs.len()];
            inst.accel().occlude_pairs_on(path, pairs, 1.0, &mut blocked);
            prop_assert_eq!(&blocked, &expected_pairs, "{:?}", path);
        }
    }
}

#[test]
fn a_mirrored_instance_keeps_its_normals_facing_out() {
    // A unit cube mirrored in x: its faces' geometric normals still point out of the box.
    let mut b = WorldBuilder::new();
    let cube = b
        .add_shared_mesh(penumbra::shapes::cube(Vec3::ONE))
        .unwrap();
    let mirror = Transform::from_srt(Vec3::new(-1.0, 1.0, 1.0), Vec3::ZERO, Vec3::ZERO);
    b.add_instance(cube, &mirror, &[0]).unwrap();
    let world = b.build(1);
    for axis in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X] {
        let ray = Ray::new(axis * 5.0, -axis);
        let hit = world.intersect(&ray, 0.0, f32::INFINITY).unwrap();
        assert!((hit.t - 4.5).abs() < 1e-5);
        let s = world.surface(&hit);
        let (n_geom, _) = s.facing(ray.direction);
        assert!((n_geom - axis).length() < 1e-5, "{axis}: {n_geom}");
    }
}

/// Where [`room`] puts copy `k`, turned by `turn` degrees and raised by `turn / 100`.
fn placement(k: usize, turn: f32) -> Transform {
    let (x, z) = ((k % 5) as f32 * 1.8 - 3.6, (k / 5) as f32 * 1.8 - 3.0);
    let mirror = if k.is_multiple_of(3) { -1.0 } else { 1.0 };
    Transform::from_srt(
        Vec3::new(mirror, 1.0 + 0.2 * (k % 2) as f32, 1.0),
        Vec3::new(0.0, 17.0 * k as f32 + turn, 0.0),
        Vec3::new(x, 0.6 + turn / 100.0, z),
    )
}

/// A lit room holding `copies` spheres (with vertex normals) and cubes, mirrored ones among
/// them: placed as instances or copied.
fn room(copies: usize, instanced: bool) -> World {
    room_turned(copies, instanced, 0.0)
}

/// [`room`] with its copies placed by [`placement`]`(k, turn)`.
fn room_turned(copies: usize, instanced: bool, turn: f32) -> World {
    use penumbra::shapes::{cube, quad, sphere};
    use penumbra::{AreaLight, Camera, Light};
    let mut b = WorldBuilder::new();
    let white = b.add_material(Material::default()).unwrap();
    let shiny = b
        .add_material(Material {
            diffuse: Vec3::new(0.7, 0.3, 0.2),
            specular: Vec3::splat(0.4),
            shininess: 40.0,
            ..Material::default()
        })
        .unwrap();
    let floor = quad(
        Vec3::new(-5.0, 0.0, 5.0),
        Vec3::new(10.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -10.0),
    );
    b.add_mesh(&floor, &Transform::IDENTITY, &[white]).unwrap();
    b.add_light(Light::Area(AreaLight {
        center: Vec3::new(0.0, 6.0, 0.0),
        u: Vec3::new(1.5, 0.0, 0.0),
        v: Vec3::new(0.0, 0.0, 1.5),
        radiance: Vec3::splat(1.0),
        n: 3,
        jitter: false,
    }));
    let camera = Camera::new(
        Vec3::new(0.0, 4.0, 9.0),
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::Y,
        50.0,
    )
    .unwrap();
    b.add_camera("main", camera).unwrap();
    let meshes = [sphere(0.6), cube(Vec3::ONE)];
    let ids = meshes.clone().map(|m| b.add_shared_mesh(m).unwrap());
    for k in 0..copies {
        let t = placement(k, turn);
        let (mesh, material) = (k % 2, if k % 2 == 0 { shiny } else { white });
        if instanced {
            b.add_instance(ids[mesh], &t, &[material]).unwrap();
        } else {
            b.add_mesh(&meshes[mesh], &t, &[material]).unwrap();
        }
    }
    b.build(2)
}

#[test]
fn an_instanced_room_renders_as_its_copies() {
    use penumbra::{render, RenderOptions, RenderSettings};
    let settings = RenderSettings {
        width: 96,
        height: 64,
        ..RenderSettings::default()
    };
    let options = RenderOptions::default();
    let (a, _) = render(&room(15, true), &settings, &options).unwrap();
    let (b, _) = render(&room(15, false), &settings, &options).unwrap();
    let mut differ = 0;
    for y in 0..settings.height {
        for x in 0..settings.width {
            let d = (a.get(x, y) - b.get(x, y)).abs().max_element();
            assert!(d < 0.05, "pixel ({x}, {y}) differs by {d}");
            differ += usize::from(d > 1e-4);
        }
    }
    // Hit points are the copies' bit for bit; only `t` (and so a shadow ray grazing an
    // edge) may round differently.
    assert!(
        differ * 200 < (settings.width * settings.height) as usize,
        "{differ} pixels differ"
    );
}

#[test]
fn an_instanced_room_has_the_same_bits_for_any_thread_count_and_region() {
    use penumbra::{render, PixelBounds, RenderOptions, RenderSettings};
    let world = room(40, true);
    let settings = RenderSettings {
        width: 72,
        height: 48,
        ..RenderSettings::default()
    };
    let run = |threads, region| {
        let options = RenderOptions {
            threads,
            region,
            ..RenderOptions::default()
        };
        render(&world, &settings, &options).unwrap().0
    };
    let one = run(1, None);
    let bits = |p: Vec3| p.to_array().map(f32::to_bits);
    let two = run(2, None);
    assert!(one
        .pixels
        .iter()
        .zip(&two.pixels)
        .all(|(a, b)| bits(*a) == bits(*b)));
    // A region whose edges cut through the batches of neighbouring pixels the full film shades
    // together: its shadow rays are grouped otherwise, and must answer alike.
    let region = PixelBounds {
        x0: 3,
        x1: 50,
        y0: 5,
        y1: 37,
    };
    let part = run(2, Some(region));
    for y in 0..part.height {
        for x in 0..part.width {
            let (a, b) = (part.get(x, y), one.get(x + region.x0, y + region.y0));
            assert_eq!(bits(a), bits(b), "region pixel ({x}, {y})");
        }
    }
}

#[test]
fn a_moved_room_renders_the_bytes_of_a_room_built_so() {
    use penumbra::{render, RenderOptions, RenderSettings, WorldError};
    let settings = RenderSettings {
        width: 64,
        height: 48,
        ..RenderSettings::default()
    };
    let image = |world: &World| {
        let film = render(world, &settings, &RenderOptions::default())
            .unwrap()
            .0;
        film.pixels
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect::<Vec<_>>()
    };
    let mut world = room(12, true);
    let still = image(&world);
    // One instance, then all of them (copy 4 twice: the later move wins).
    world.set_transform(4, &placement(4, 200.0)).unwrap();
    let mut moves: Vec<_> = (0..12).map(|k| (k, placement(k, 30.0))).collect();
    moves.push((4, placement(4, 30.0)));
    world.set_transforms(&moves).unwrap();
    let moved = image(&world);
    assert_ne!(moved, still, "the move shows");
    assert_eq!(moved, image(&room_turned(12, true, 30.0)));
    // A refused move changes nothing.
    let singular = Transform::from_srt(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
    let refused = world.set_transforms(&[(0, placement(0, 90.0)), (1, singular)]);
    assert_eq!(refused, Err(WorldError::SingularTransform));
    let unknown = world.set_transform(12, &placement(0, 0.0));
    assert!(matches!(
        unknown,
        Err(WorldError::UnknownInstance {
            index: 12,
            instances: 12
        })
    ));
    assert_eq!(image(&world), moved);
}

#[test]
fn instances_of_an_empty_mesh_are_objects_that_nothing_hits() {
    let mut b = WorldBuilder::new();
    let empty = b.add_shared_mesh(Mesh::default()).unwrap();
    let cube = b
        .add_shared_mesh(penumbra::shapes::cube(Vec3::ONE))
        .unwrap();
    for k in 0..3 {
        let t = Transform::from_srt(Vec3::ONE, Vec3::ZERO, Vec3::new(2.0 * k as f32, 0.0, 0.0));
        b.add_instance(empty, &t, &[0]).unwrap();
        b.add_instance(cube, &t, &[0]).unwrap();
    }
    let world = b.build(1);
    assert_eq!(world.stats().objects, 6);
    let hit = world.intersect(
        &Ray::new(Vec3::new(2.0, 0.0, 5.0), -Vec3::Z),
        0.0,
        f32::INFINITY,
    );
    assert_eq!(hit.map(|h| world.surface(&h).object), Some(3));
    assert!(world.bounds().max.x < 4.6, "{:?}", world.bounds());
}
