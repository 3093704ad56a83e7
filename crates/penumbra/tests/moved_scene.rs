//! Objects placed by a `matrix`, and scene files with an object moved
//! (`SceneFile::with_transform`, what Python's `Scene.set_transform` calls): a moved file
//! builds the bytes of a file written with the new transform, its pack builds them too, moves
//! of one object do not pile up, and bad moves are refused at their key.

mod support;

use penumbra::{render, RenderOptions, Scene, SceneFile, SceneFormat, ScenePack};
use support::{TempDir, CUBE_OBJ as CUBE};

const HEAD: &str = r#"[film]
width = 40
height = 30
[camera]
position = [0, 1, 12]
look_at = [0, 0, 0]
fov = 40
[[lights]]
type = "point"
position = [3, 6, 8]
intensity = 60
[materials.red]
diffuse = [0.8, 0.1, 0.1]
[materials.blue]
diffuse = [0.1, 0.1, 0.8]
"#;

/// A sphere, a mesh object and two placements of the cube.
const OBJECTS: &str = r#"
[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "red"
translate = [-2, 0, 0]
[[objects]]
type = "mesh"
file = "cube.obj"
rotate = [0, 30, 0]
[[objects]]
type = "instances"
file = "cube.obj"
material = "blue"
translate = [0, -1, 0]
transforms = [{ translate = [2, 0, 0] }, { translate = [0, 2, 0], material = "red" }]
"#;

/// A turn about y by 90° and a shift, by rows, written out in the file's way too.
const TURN: [[f64; 4]; 4] = [
    [0.0, 0.0, 1.0, 0.5],
    [0.0, 1.0, 0.0, -0.25],
    [-1.0, 0.0, 0.0, 1.5],
    [0.0, 0.0, 0.0, 1.0],
];
const TURN_TEXT: &str = "[[0, 0, 1, 0.5], [0, 1, 0, -0.25], [-1, 0, 0, 1.5], [0, 0, 0, 1]]";

fn file(dir: &TempDir, objects: &str) -> SceneFile {
    let text = format!("{HEAD}{objects}");
    let path = dir.write("scene.toml", &text);
    SceneFile::from_str(&text, SceneFormat::Toml, &path, dir.path())
        .unwrap()
        .keeping_files()
}

/// Every pixel's bits.
fn pixels(scene: &Scene) -> Vec<[u32; 3]> {
    let (film, _) = render(&scene.world, &scene.settings, &RenderOptions::default()).unwrap();
    film.pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

#[test]
fn an_object_matrix_renders_the_bytes_of_the_same_scale_and_translation() {
    let dir = TempDir::new("moved_matrix_key");
    dir.write("cube.obj", CUBE);
    let srt = "[[objects]]\ntype = \"cube\"\ncenter = [0, 0, 0]\nsize = 1\n\
               scale = [2, 1, 1]\ntranslate = [1, 0, -2]\n";
    let matrix = "[[objects]]\ntype = \"cube\"\ncenter = [0, 0, 0]\nsize = 1\n\
                  matrix = [[2, 0, 0, 1], [0, 1, 0, 0], [0, 0, 1, -2], [0, 0, 0, 1]]\n";
    let a = pixels(&file(&dir, srt).build(1).unwrap());
    let b = pixels(&file(&dir, matrix).build(1).unwrap());
    assert_eq!(a, b);
    assert!(a.iter().any(|p| p[0] != 0), "the cube is in view");
}

#[test]
fn an_object_matrix_is_checked_as_a_placements_is() {
    let dir = TempDir::new("moved_matrix_bad");
    let cases = [
        ("matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\ntranslate = [1, 0, 0]", "one or the other"),
        ("matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]]", "not affine"),
        ("matrix = [[1, 0, 0, 0], [0, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]", "cannot be inverted"),
    ];
    for (keys, words) in cases {
        let object =
            format!("[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n{keys}\n");
        let e = file(&dir, &object).build(1).unwrap_err().to_string();
        assert!(
            e.contains("objects[0].matrix") && e.contains(words),
            "{keys}: {e}"
        );
    }
}

#[test]
fn a_moved_object_builds_the_bytes_of_a_file_written_so() {
    let dir = TempDir::new("moved_object");
    dir.write("cube.obj", CUBE);
    let original = file(&dir, OBJECTS);
    let cases = [
        // The sphere, the mesh object, a whole instances object, and one placement of it.
        (
            0,
            None,
            "radius = 1\nmaterial = \"red\"\ntranslate = [-2, 0, 0]\n",
            "radius = 1\nmaterial = \"red\"\nmatrix = M\n",
        ),
        (
            1,
            None,
            "file = \"cube.obj\"\nrotate = [0, 30, 0]\n",
            "file = \"cube.obj\"\nmatrix = M\n",
        ),
        (
            2,
            None,
            "material = \"blue\"\ntranslate = [0, -1, 0]\n",
            "material = \"blue\"\nmatrix = M\n",
        ),
        (
            2,
            Some(1),
            "{ translate = [0, 2, 0], material = \"red\" }",
            "{ matrix = M, material = \"red\" }",
        ),
    ];
    let before = pixels(&original.build(1).unwrap());
    for (object, placement, from, to) in cases {
        let moved = original.with_transform(object, placement, TURN).unwrap();
        let written = OBJECTS.replace(from, &to.replace('M', TURN_TEXT));
        assert_ne!(written, OBJECTS);
        let fresh = file(&dir, &written);
        let image = pixels(&moved.build(1).unwrap());
        assert_eq!(
            image,
            pixels(&fresh.build(1).unwrap()),
            "{object} {placement:?}"
        );
        assert_ne!(image, before, "{object} {placement:?} moved in view");
        // A pack of the moved file builds the moved scene, from the bytes it holds.
        let pack: ScenePack = moved.pack(&moved.build(1).unwrap().files).unwrap();
        assert_eq!(pixels(&pack.load().unwrap().build(1).unwrap()), image);
    }
}

#[test]
fn moves_of_one_object_do_not_pile_up() {
    let dir = TempDir::new("moved_again");
    dir.write("cube.obj", CUBE);
    let original = file(&dir, OBJECTS);
    let once = original.with_transform(2, Some(0), TURN).unwrap();
    let mut again = original.clone();
    for k in 0..50 {
        let mut m = TURN;
        m[0][3] = f64::from(k);
        again = again.with_transform(2, Some(0), m).unwrap();
    }
    again = again.with_transform(2, Some(0), TURN).unwrap();
    assert_eq!(again.digest(&[]), once.digest(&[]));
    assert_ne!(once.digest(&[]), original.digest(&[]));
    // A move of the whole object takes the moves of its placements in.
    let object = once.with_transform(2, None, TURN).unwrap();
    let direct = original
        .with_transform(2, Some(0), TURN)
        .unwrap()
        .with_transform(2, None, TURN)
        .unwrap();
    assert_eq!(object.digest(&[]), direct.digest(&[]));
    assert_eq!(
        pixels(&object.build(1).unwrap()),
        pixels(&direct.build(1).unwrap())
    );
}

#[test]
fn bad_moves_are_refused_at_their_key() {
    let dir = TempDir::new("moved_bad");
    dir.write("cube.obj", CUBE);
    let npy = "[[objects]]\ntype = \"instances\"\nfile = \"cube.obj\"\ntransforms = \"t.npy\"\n";
    let mut singular = TURN;
    singular[1] = [0.0; 4];
    let mut nan = TURN;
    nan[2][1] = f64::NAN;
    let mut projective = TURN;
    projective[3][0] = 1.0;
    type Case<'a> = (
        &'a str,
        usize,
        Option<usize>,
        [[f64; 4]; 4],
        &'a str,
        &'a str,
    );
    let cases: [Case; 7] = [
        (OBJECTS, 3, None, TURN, "objects", "no object 3"),
        (OBJECTS, 0, Some(0), TURN, "objects[0]", "no placements"),
        (
            OBJECTS,
            2,
            Some(2),
            TURN,
            "objects[2].transforms",
            "no placement 2",
        ),
        (npy, 0, Some(0), TURN, "objects[0].transforms", ".npy"),
        (OBJECTS, 1, None, nan, "objects[1].matrix", "NaN"),
        (
            OBJECTS,
            1,
            None,
            singular,
            "objects[1].matrix",
            "cannot be inverted",
        ),
        (
            OBJECTS,
            2,
            Some(1),
            projective,
            "objects[2].transforms[1].matrix",
            "not affine",
        ),
    ];
    for (objects, object, placement, m, key, words) in cases {
        let e = match file(&dir, objects).with_transform(object, placement, m) {
            Ok(moved) => moved.build(1).map(|_| ()).unwrap_err(),
            Err(e) => e,
        };
        let text = e.to_string();
        assert!(text.contains(key) && text.contains(words), "{key}: {text}");
    }
}

/// A grid of `n`×`n` squares (2n² triangles) in the unit square of z = 0, as an OBJ file.
fn grid_obj(n: usize) -> String {
    let mut obj = String::new();
    for j in 0..=n {
        for i in 0..=n {
            obj += &format!(
                "v {} {} 0\n",
                i as f32 / n as f32 - 0.5,
                j as f32 / n as f32 - 0.5
            );
        }
    }
    let v = |i: usize, j: usize| j * (n + 1) + i + 1;
    for j in 0..n {
        for i in 0..n {
            obj += &format!("f {} {} {}\n", v(i, j), v(i + 1, j), v(i + 1, j + 1));
            obj += &format!("f {} {} {}\n", v(i, j), v(i + 1, j + 1), v(i, j + 1));
        }
    }
    obj
}

#[test]
fn moved_instances_are_moved_in_the_world_as_a_fresh_build_places_them() {
    let dir = TempDir::new("moved_instances");
    // 40 copies of 32,768 triangles: more than penumbra copies, so they are instances.
    dir.write("grid.obj", grid_obj(128));
    dir.write("cube.obj", CUBE);
    let rows: Vec<String> = (0..40)
        .map(|k| {
            format!(
                "{{ translate = [{}, {}, 0], scale = 0.8 }}",
                k % 8 - 4,
                k / 8 - 2
            )
        })
        .collect();
    let objects = format!(
        "{OBJECTS}[[objects]]\ntype = \"instances\"\nfile = \"grid.obj\"\nrotate = [0, 20, 0]\n\
         transforms = [{}]\n",
        rows.join(", ")
    );
    let original = file(&dir, &objects);
    let scene = original.build(1).unwrap();
    assert_eq!(scene.world.stats().instances, 40);
    for placement in [None, Some(17)] {
        let moved = original.with_transform(3, placement, TURN).unwrap();
        let world = moved
            .moved_world(3, &scene.world, scene.objects[3].clone())
            .unwrap()
            .expect("instances move in place");
        let fresh = moved.build(1).unwrap();
        let image = pixels(&Scene {
            world: std::sync::Arc::new(world),
            ..fresh.clone()
        });
        assert_eq!(image, pixels(&fresh), "{placement:?}");
        assert_ne!(image, pixels(&scene), "{placement:?} moved in view");
    }
    // Copies of a file copied into the world's triangles move only by a build.
    let moved = original.with_transform(2, Some(0), TURN).unwrap();
    let world = moved.moved_world(2, &scene.world, scene.objects[2].clone());
    assert!(world.unwrap().is_none());
    // A move the build refuses is refused alike, at the same key: a matrix that cannot be
    // inverted, a copy put past the coordinates penumbra renders exactly.
    let mut singular = TURN;
    singular[2] = [0.0; 4];
    let far = [
        [3e12, 0.0, 0.0, 0.0],
        [0.0, 3e12, 0.0, 0.0],
        [0.0, 0.0, 3e12, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    for m in [singular, far] {
        let moved = original.with_transform(3, Some(3), m).unwrap();
        let e = moved
            .moved_world(3, &scene.world, scene.objects[3].clone())
            .unwrap_err();
        assert_eq!(e.to_string(), moved.build(1).unwrap_err().to_string());
        assert!(e.to_string().contains("objects[3].transforms[3]"), "{e}");
    }
}

#[test]
fn moved_instances_are_checked_for_scale_as_a_build_checks_them() {
    let dir = TempDir::new("moved_scale");
    dir.write("grid.obj", grid_obj(128));
    let text = format!(
        "{}[[objects]]\ntype = \"instances\"\nfile = \"grid.obj\"\nrotate = [0, 20, 0]\n\
         transforms = [{}]\n",
        HEAD.replace("position = [0, 1, 12]", "position = [0, 1, 1e18]"),
        vec!["{ scale = 0.8 }"; 40].join(", ")
    );
    let path = dir.write("scene.toml", &text);
    let original = SceneFile::from_str(&text, SceneFormat::Toml, &path, dir.path())
        .unwrap()
        .keeping_files();
    let scene = original.build(1).unwrap();
    // Within the coordinates, but edges so long that a camera this far overflows.
    let huge = [
        [1e12, 0.0, 0.0, 0.0],
        [0.0, 1e12, 0.0, 0.0],
        [0.0, 0.0, 1e12, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let moved = original.with_transform(0, Some(5), huge).unwrap();
    let e = moved
        .moved_world(0, &scene.world, scene.objects[0].clone())
        .unwrap_err();
    assert_eq!(e.to_string(), moved.build(1).unwrap_err().to_string());
    assert!(e.to_string().contains("camera.position"), "{e}");
}

#[test]
fn any_scene_a_file_loads_moves_json_and_line_breaks_included() {
    let dir = TempDir::new("moved_any");
    // A material name with a line break, and a seed beyond TOML's integers (JSON).
    let toml = format!(
        "{HEAD}[materials.\"a\\nb\"]\ndiffuse = [0.2, 0.9, 0.2]\n\
         [[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"a\\nb\"\n"
    );
    let json = r#"{"film": {"width": 40, "height": 30},
        "camera": {"position": [0, 1, 12], "look_at": [0, 0, 0], "fov": 40},
        "render": {"seed": 18446744073709551615, "sampler": "jittered", "samples": 4},
        "lights": [{"type": "point", "position": [3, 6, 8], "intensity": 60}],
        "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "translate": [1, 0, 0]}]}"#;
    for (text, format) in [
        (toml.as_str(), SceneFormat::Toml),
        (json, SceneFormat::Json),
    ] {
        let original = SceneFile::from_str(text, format, "s", dir.path()).unwrap();
        let moved = original.with_transform(0, None, TURN).unwrap();
        assert_eq!(moved.desc.objects[0].matrix.map(|m| m[0][3].0), Some(0.5));
        let image = pixels(&moved.build(1).unwrap());
        assert_ne!(image, pixels(&original.build(1).unwrap()));
        // The pack, read again, builds the same.
        let pack = moved.pack(&[]).unwrap();
        assert_eq!(pixels(&pack.load().unwrap().build(1).unwrap()), image);
    }
}

#[test]
fn named_objects_are_found_by_name_listed_with_it_and_rendered_as_unnamed() {
    let dir = TempDir::new("moved_names");
    dir.write("cube.obj", CUBE);
    let named = OBJECTS
        .replacen("type = \"sphere\"", "name = \"ball\"\ntype = \"sphere\"", 1)
        .replacen(
            "type = \"instances\"",
            "name = \"herd\"\ntype = \"instances\"",
            1,
        );
    let file_named = file(&dir, &named);
    assert_eq!(file_named.object_index("herd").unwrap(), 2);
    assert_eq!(file_named.object_index("ball").unwrap(), 0);
    let e = file_named.object_index("box").unwrap_err().to_string();
    assert!(
        e.contains("no object named `box`") && e.contains("`ball`, `herd`"),
        "{e}"
    );
    // A name changes nothing in the image, and the records name the entry's ids by it.
    let scene = file_named.build(1).unwrap();
    assert_eq!(
        pixels(&scene),
        pixels(&file(&dir, OBJECTS).build(1).unwrap())
    );
    let entries = penumbra::products::record::objects(&file_named, &scene.objects);
    let names: Vec<Option<&str>> = entries.iter().map(|o| o.name.as_deref()).collect();
    assert_eq!(names, [Some("ball"), None, Some("herd")]);
    assert_eq!(entries[2].ids, [2, 4]);
    // A name is one object's, and not empty.
    for (objects, key, words) in [
        (
            named.replacen("name = \"herd\"", "name = \"ball\"", 1),
            "objects[2].name",
            "already the name of objects[0]",
        ),
        (
            named.replacen("name = \"herd\"", "name = \"\"", 1),
            "objects[2].name",
            "not empty",
        ),
    ] {
        let e = file(&dir, &objects).build(1).unwrap_err().to_string();
        assert!(e.contains(key) && e.contains(words), "{e}");
    }
}
