//! `type = "instances"` and shared mesh files in scene files: where the copies go, which
//! material and object id each has, when a file is copied and when it is built once, and the
//! errors of inline placements and `.npy` files, each at its key.

mod support;

use glam::Vec3;
use penumbra::{AssetKind, ErrorKind, Ray, Scene, SceneError, SceneFile, SceneFormat};
use support::{npy, TempDir, CUBE_OBJ as CUBE};

const HEAD: &str = r#"[film]
width = 32
height = 24
[camera]
position = [0, 0, 20]
look_at = [0, 0, 0]
fov = 40
[materials.red]
diffuse = [0.8, 0.1, 0.1]
[materials.blue]
diffuse = [0.1, 0.1, 0.8]
"#;

fn build(dir: &TempDir, objects: &str) -> Result<Scene, SceneError> {
    let text = format!("{HEAD}{objects}");
    let path = dir.write("scene.toml", &text);
    let file = SceneFile::from_str(&text, SceneFormat::Toml, &path, dir.path())?;
    file.build(1)
}

/// The object id and material of what the ray from `from` toward −z meets.
fn hit_at(scene: &Scene, x: f32, y: f32) -> Option<(u32, u32)> {
    let ray = Ray::new(Vec3::new(x, y, 10.0), -Vec3::Z);
    let hit = scene.world.intersect(&ray, 0.0, f32::INFINITY)?;
    let s = scene.world.surface(&hit);
    Some((s.object, s.material))
}

#[test]
fn inline_placements_go_where_they_say_with_their_materials_and_ids() {
    let dir = TempDir::new("inst_inline");
    dir.write("cube.obj", CUBE);
    let scene = build(
        &dir,
        r#"
[[objects]]
type = "cube"
center = [0, -5, 0]
size = 1
[[objects]]
type = "instances"
file = "cube.obj"
material = "red"
translate = [0, 1, 0]
transforms = [
  { translate = [-3, 0, 0] },
  { translate = [0, 0, 0], scale = [1, 2, 1], material = "blue" },
  { matrix = [[1, 0, 0, 3], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]] },
]
"#,
    )
    .unwrap();
    // The cube is object 0; the copies are 1, 2 and 3, each moved by the object's translate.
    assert_eq!(scene.objects, [0..1, 1..4]);
    let (red, blue) = (1, 2);
    assert_eq!(hit_at(&scene, -3.0, 1.0), Some((1, red)));
    assert_eq!(hit_at(&scene, 0.0, 1.9), Some((2, blue)));
    assert_eq!(hit_at(&scene, 3.0, 1.0), Some((3, red)));
    assert_eq!(hit_at(&scene, 3.0, 1.9), None);
    assert_eq!(hit_at(&scene, 0.0, -5.0), Some((0, 0)));
}

#[test]
fn a_small_mesh_placed_a_few_times_is_copied_and_a_large_one_is_built_once() {
    let dir = TempDir::new("inst_rule");
    dir.write("cube.obj", CUBE);
    let copies = |n: usize| {
        let list: Vec<String> = (0..n)
            .map(|i| format!("{{ translate = [{}, 0, 0] }}", i as f32 * 0.01))
            .collect();
        format!(
            "[[objects]]\ntype = \"instances\"\nfile = \"cube.obj\"\ntransforms = [{}]\n\
             [[objects]]\ntype = \"mesh\"\nfile = \"cube.obj\"\n",
            list.join(", ")
        )
    };
    // 3 + 1 copies of 12 triangles: copied, as separate objects would be.
    let s = build(&dir, &copies(3)).unwrap().world.stats();
    assert_eq!((s.triangles, s.unique_triangles, s.instances), (48, 48, 0));
    // 2^20 / 12 copies and more: built once.
    let n = (1 << 20) / 12 + 1;
    let s = build(&dir, &copies(n)).unwrap().world.stats();
    assert_eq!(s.triangles, 12 * (n + 1));
    assert_eq!((s.unique_triangles, s.meshes, s.instances), (12, 1, n + 1));
}

/// Row-major float32 translations by (x, 0, 0).
fn translations(xs: &[f32]) -> Vec<u8> {
    xs.iter()
        .flat_map(|&x| {
            [
                1.0, 0.0, 0.0, x, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0f32,
            ]
        })
        .flat_map(f32::to_le_bytes)
        .collect()
}

#[test]
fn npy_transforms_place_copies_and_bad_files_are_errors_at_the_key() {
    let dir = TempDir::new("inst_npy");
    dir.write("cube.obj", CUBE);
    let object = "[[objects]]\ntype = \"instances\"\nfile = \"cube.obj\"\ntransforms = \"t.npy\"\n";
    dir.write(
        "t.npy",
        npy("<f4", "(2, 4, 4)", &translations(&[-2.0, 2.0])),
    );
    let scene = build(&dir, object).unwrap();
    assert_eq!(scene.objects, vec![std::ops::Range { start: 0, end: 2 }]);
    assert_eq!(hit_at(&scene, -2.0, 0.0).map(|h| h.0), Some(0));
    assert_eq!(hit_at(&scene, 2.0, 0.0).map(|h| h.0), Some(1));
    assert_eq!(hit_at(&scene, 0.0, 0.0), None);
    assert!(scene.files.iter().any(|f| f.ends_with("t.npy")));

    let mut singular = translations(&[0.0]);
    singular[..4].copy_from_slice(&0.0f32.to_le_bytes());
    let mut nan = translations(&[0.0]);
    nan[20..24].copy_from_slice(&f32::NAN.to_le_bytes());
    let asset = ErrorKind::Asset(AssetKind::Transforms);
    let cases: [(Vec<u8>, ErrorKind, &str, &str); 5] = [
        (
            npy("<f4", "(1, 3, 4)", &translations(&[0.0])[..48]),
            asset,
            "objects[0].transforms",
            "shape (1, 3, 4)",
        ),
        (
            npy("<i4", "(1, 4, 4)", &translations(&[0.0])),
            asset,
            "objects[0].transforms",
            "float32 or float64",
        ),
        (
            npy("<f4", "(1, 4, 4)", &nan),
            asset,
            "objects[0].transforms",
            "matrix 0 has an entry that is not a finite number",
        ),
        (
            npy("<f4", "(1, 4, 4)", &singular),
            ErrorKind::BadValue,
            "objects[0].transforms[0]",
            "cannot be inverted",
        ),
        (
            npy("<f4", "(3, 4, 4)", &translations(&[0.0])),
            asset,
            "objects[0].transforms",
            "ends before its 3 matrices",
        ),
    ];
    for (bytes, kind, key, words) in cases {
        dir.write("t.npy", bytes);
        let e = build(&dir, object).unwrap_err();
        let SceneError::Invalid {
            kind: k,
            location,
            message,
        } = &e
        else {
            panic!("{e}");
        };
        assert_eq!((*k, location.key.as_deref()), (kind, Some(key)), "{e}");
        assert!(message.contains(words), "{e}");
    }
}

#[test]
fn a_hundred_million_transforms_are_refused_before_they_are_read() {
    let dir = TempDir::new("inst_huge");
    dir.write("cube.obj", CUBE);
    // A sparse file as large as 10^8 float32 matrices: refused from its size alone.
    let path = dir.write("t.npy", npy("<f4", "(100000000, 4, 4)", &[]));
    let file = std::fs::OpenOptions::new().write(true).open(&path).unwrap();
    file.set_len(128 + 100_000_000 * 64).unwrap();
    let object = "[[objects]]\ntype = \"instances\"\nfile = \"cube.obj\"\ntransforms = \"t.npy\"\n";
    let e = build(&dir, object).unwrap_err().to_string();
    assert!(
        e.contains("objects[0].transforms") && e.contains("at most 16777216"),
        "{e}"
    );
}

#[test]
fn inline_placement_mistakes_are_errors_at_their_key() {
    let dir = TempDir::new("inst_bad");
    dir.write("cube.obj", CUBE);
    let cases = [
        ("{ matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], translate = [1, 0, 0] }", "objects[0].transforms[0].matrix", "one or the other"),
        ("{ matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]] }", "objects[0].transforms[0].matrix", "not affine"),
        ("{ scale = [1, 0, 1] }", "objects[0].transforms[0]", "cannot be inverted"),
        ("{ material = \"green\" }", "objects[0].transforms[0].material", "green"),
    ];
    for (entry, key, words) in cases {
        let object = format!(
            "[[objects]]\ntype = \"instances\"\nfile = \"cube.obj\"\ntransforms = [{entry}]\n"
        );
        let e = build(&dir, &object).unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains(key) && text.contains(words),
            "{entry}: {text}"
        );
    }
    // An unknown key in an entry is a parse error naming it.
    let object =
        "[[objects]]\ntype = \"instances\"\nfile = \"cube.obj\"\ntransforms = [{ shift = 1 }]\n";
    let e = build(&dir, object).unwrap_err().to_string();
    assert!(e.contains("shift"), "{e}");
}
