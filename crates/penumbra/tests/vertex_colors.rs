//! Vertex colours through the public API: a colour multiplies the diffuse and ambient colours
//! exactly as the same factor on the material would, under both light models, for copies and
//! instances; colours vary across a triangle; the albedo AOV includes them.

use glam::Vec3;
use penumbra::{
    render, render_with_aovs, shapes::sphere, AreaLight, Camera, Film, Light, LightModel, Material,
    Mesh, PointLight, RenderOptions, RenderSettings, Rgb, Transform, World, WorldBuilder,
};

/// Powers of two, so that their products with the material are exact.
const TINT: Rgb = Rgb::new(0.5, 0.25, 1.0);

/// A shiny sphere and a floor quad under an area light and a point light. The meshes carry
/// the vertex colour `tint` (if any) and are placed as copies or as instances; their material
/// has the diffuse and ambient colours `diffuse`.
fn world(tint: Option<Rgb>, diffuse: Rgb, instanced: bool) -> World {
    let mut b = WorldBuilder::new();
    let m = b
        .add_material(Material {
            diffuse,
            ambient: diffuse,
            specular: Rgb::splat(0.3),
            shininess: 12.0,
            ..Material::default()
        })
        .unwrap();
    let floor = Mesh {
        positions: vec![
            Vec3::new(-3.0, 0.0, -3.0),
            Vec3::new(-3.0, 0.0, 3.0),
            Vec3::new(3.0, 0.0, 3.0),
            Vec3::new(3.0, 0.0, -3.0),
        ],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        ..Mesh::default()
    };
    let lift = Transform::from_srt(Vec3::ONE, Vec3::ZERO, Vec3::new(0.0, 1.0, 0.0));
    for (mut mesh, at) in [(floor, Transform::IDENTITY), (sphere(0.9), lift)] {
        if let Some(c) = tint {
            mesh.colors = vec![c; mesh.positions.len()];
        }
        if instanced {
            let id = b.add_shared_mesh(mesh).unwrap();
            b.add_instance(id, &at, &[m]).unwrap();
        } else {
            b.add_mesh(&mesh, &at, &[m]).unwrap();
        }
    }
    b.add_light(Light::Area(AreaLight {
        center: Vec3::new(0.5, 4.0, 1.0),
        u: Vec3::new(1.0, 0.0, 0.0),
        v: Vec3::new(0.0, 0.0, 1.0),
        radiance: Rgb::splat(3.0),
        n: 3,
        jitter: false,
    }));
    b.add_light(Light::Point(PointLight {
        position: Vec3::new(-2.0, 3.0, 2.0),
        intensity: Rgb::splat(2.0),
    }));
    let camera = Camera::new(
        Vec3::new(0.0, 2.5, 5.0),
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::Y,
        45.0,
    );
    b.add_camera("main", camera.unwrap()).unwrap();
    b.build(1)
}

fn settings(light_model: LightModel) -> RenderSettings {
    RenderSettings {
        width: 48,
        height: 32,
        light_model,
        ..RenderSettings::default()
    }
}

fn film(world: &World, light_model: LightModel) -> Film {
    render(world, &settings(light_model), &RenderOptions::default())
        .unwrap()
        .0
}

#[test]
fn a_vertex_colour_scales_diffuse_and_ambient_like_the_material() {
    let diffuse = Rgb::new(0.75, 0.5, 0.25);
    for light_model in [LightModel::Phong, LightModel::Physical] {
        let tinted_material = film(&world(None, TINT * diffuse, false), light_model);
        for instanced in [false, true] {
            let colored = film(&world(Some(TINT), diffuse, instanced), light_model);
            // Only instancing's own rounding (rays enter the mesh in object space) may
            // differ from the copies.
            let close = |a: Rgb, b: Rgb| (a - b).abs().max_element() <= 1e-4 * a.max_element();
            let same = colored
                .pixels
                .iter()
                .zip(&tinted_material.pixels)
                .all(|(&a, &b)| if instanced { close(a, b) } else { a == b });
            assert!(same, "{light_model:?}, instanced: {instanced}");
        }
        let white = film(&world(None, diffuse, false), light_model);
        assert_ne!(white, tinted_material, "{light_model:?}");
    }
}

#[test]
fn colours_are_interpolated_across_a_triangle() {
    let mut b = WorldBuilder::new();
    let red_to_blue = Mesh {
        positions: vec![
            Vec3::new(-3.0, -1.0, 0.0),
            Vec3::new(3.0, -1.0, 0.0),
            Vec3::new(3.0, 1.0, 0.0),
            Vec3::new(-3.0, 1.0, 0.0),
        ],
        colors: vec![Rgb::X, Rgb::Z, Rgb::Z, Rgb::X],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        ..Mesh::default()
    };
    b.add_mesh(&red_to_blue, &Transform::IDENTITY, &[0])
        .unwrap();
    b.add_light(Light::Point(PointLight {
        position: Vec3::new(0.0, 0.0, 3.0),
        intensity: Rgb::ONE,
    }));
    let camera = Camera::new(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 30.0);
    b.add_camera("main", camera.unwrap()).unwrap();
    let world = b.build(1);
    let s = RenderSettings {
        width: 9,
        height: 3,
        ..RenderSettings::default()
    };
    let (film, aovs, _) = render_with_aovs(&world, &s, &RenderOptions::default()).unwrap();
    // Red at x = −3, blue at x = 3; the film spans x ∈ [−2.4, 2.4].
    let (left, middle, right) = (film.get(0, 1), film.get(4, 1), film.get(8, 1));
    assert!(left.x > 3.0 * left.z && left.y == 0.0, "{left}");
    assert!(right.z > 3.0 * right.x && right.y == 0.0, "{right}");
    assert!((middle.x - middle.z).abs() < 0.1 * middle.x, "{middle}");
    // The albedo is the default material's 0.8 grey times the colour.
    let albedo = aovs.get(4, 1).albedo;
    assert!(
        (albedo - Rgb::new(0.4, 0.0, 0.4)).abs().max_element() < 0.05,
        "{albedo}"
    );
    let albedo = aovs.get(0, 1).albedo;
    assert!(albedo.x > 3.0 * albedo.z, "{albedo}");
}
