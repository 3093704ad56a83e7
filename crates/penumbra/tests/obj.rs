//! The Wavefront OBJ/MTL loader through the public API: small files written into a temporary
//! folder per test, plus the real assets under `assets/` at the repository root.

mod support;

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use penumbra::TextureKind;
use penumbra::{Scene, SceneError, SceneFile, SceneFormat};
use support::TempDir;

/// A scene with a tiny film and a camera, then `body` (materials, textures, objects).
fn scene_text(body: &str) -> String {
    format!(
        "[film]\nwidth = 4\nheight = 4\n\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\
         fov = 40\n\n{body}\n"
    )
}

/// Builds a scene whose files live in `dir`.
fn try_build(dir: &Path, body: &str) -> Result<Scene, SceneError> {
    let text = scene_text(body);
    let file = SceneFile::from_str(&text, SceneFormat::Toml, "x.toml", dir)?;
    file.build(0)
}

fn build(dir: &Path, body: &str) -> Scene {
    try_build(dir, body).unwrap_or_else(|e| panic!("{e}"))
}

/// A scene with the single object `mesh` loading `file`.
fn mesh(dir: &Path, file: &str) -> Scene {
    build(
        dir,
        &format!("[[objects]]\ntype = \"mesh\"\nfile = \"{file}\"\n"),
    )
}

fn mesh_error(dir: &Path, file: &str) -> String {
    match try_build(
        dir,
        &format!("[[objects]]\ntype = \"mesh\"\nfile = \"{file}\"\n"),
    ) {
        Ok(_) => panic!("{file} should not load"),
        Err(e) => e.to_string(),
    }
}

fn tri_positions(scene: &Scene, i: usize) -> [Vec3; 3] {
    scene.world.geometry().corners(i)
}

fn tri_uvs(scene: &Scene, i: usize) -> [Vec2; 3] {
    scene.world.geometry().triangles[i]
        .vertices
        .map(|v| scene.world.geometry().uvs[v as usize])
}

fn tri_normals(scene: &Scene, i: usize) -> [Vec3; 3] {
    scene.world.geometry().triangles[i]
        .vertices
        .map(|v| scene.world.geometry().normals[v as usize])
}

fn tri_diffuse(scene: &Scene, i: usize) -> Vec3 {
    scene.world.materials()[scene.world.geometry().triangles[i].material as usize].diffuse
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

/// Five corners of a convex pentagon in the z = 0 plane, as OBJ `v` lines and as vectors.
const PENTAGON: [[f32; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [2.0, 0.0, 0.0],
    [3.0, 1.0, 0.0],
    [1.0, 2.0, 0.0],
    [-1.0, 1.0, 0.0],
];

fn v_lines(points: &[[f32; 3]]) -> String {
    points
        .iter()
        .map(|p| format!("v {} {} {}\n", p[0], p[1], p[2]))
        .collect()
}

fn p(i: usize) -> Vec3 {
    Vec3::from(PENTAGON[i])
}

#[test]
fn triangle() {
    let dir = TempDir::new("triangle");
    dir.write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let scene = mesh(dir.path(), "t.obj");
    assert_eq!(scene.world.stats().triangles, 1);
    assert_eq!(
        tri_positions(&scene, 0),
        [Vec3::ZERO, Vec3::X, Vec3::Y],
        "corners in file order"
    );
    let t = scene.world.geometry().triangles[0];
    assert!(!t.smooth, "no vn: flat shading");
    assert_eq!(t.material, 0, "no usemtl: the default material");
    assert_eq!(tri_uvs(&scene, 0), [Vec2::ZERO; 3], "no vt: uv (0, 0)");
}

#[test]
fn quad_and_pentagon_are_fan_triangulated() {
    let dir = TempDir::new("fan");
    dir.write(
        "fan.obj",
        format!("{}f 1 2 3 4\nf 1 2 3 4 5\n", v_lines(&PENTAGON)),
    );
    let scene = mesh(dir.path(), "fan.obj");
    assert_eq!(scene.world.stats().triangles, 2 + 3);
    let expected = [[0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 2, 3], [0, 3, 4]];
    for (i, e) in expected.iter().enumerate() {
        assert_eq!(
            tri_positions(&scene, i),
            e.map(p),
            "triangle {i}: fan (0, i, i+1)"
        );
    }
}

#[test]
fn negative_indices_are_relative_to_what_is_defined_so_far() {
    let dir = TempDir::new("negative");
    dir.write(
        "neg.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n\
         f -4/-4/-1 -3/-3/-1 -2/-2/-1 -1/-1/-1\n\
         v 5 0 0\nv 6 0 0\nv 5 1 0\n\
         f -3 -2 -1\n\
         f 1/1 -1/-2 -6/-1\n",
    );
    let scene = mesh(dir.path(), "neg.obj");
    assert_eq!(scene.world.stats().triangles, 4);
    let (v, vt) = (
        [
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::Y,
            Vec3::new(5.0, 0.0, 0.0),
            Vec3::new(6.0, 0.0, 0.0),
            Vec3::new(5.0, 1.0, 0.0),
        ],
        [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
    );
    assert_eq!(tri_positions(&scene, 0), [v[0], v[1], v[2]]);
    assert_eq!(tri_positions(&scene, 1), [v[0], v[2], v[3]]);
    assert_eq!(tri_uvs(&scene, 1), [vt[0], vt[2], vt[3]]);
    assert_eq!(tri_positions(&scene, 2), [v[4], v[5], v[6]]);
    assert_eq!(tri_positions(&scene, 3), [v[0], v[6], v[1]]);
    assert_eq!(tri_uvs(&scene, 3), [vt[0], vt[2], vt[3]]);
}

#[test]
fn corner_forms_v_vt_vn() {
    let dir = TempDir::new("forms");
    let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.25 0.5\nvt 0.75 0.5\nvt 0.5 1\n\
                vn 0 0 1\nvn 0 1 1\nvn 1 0 1\n";
    let uvs = [
        Vec2::new(0.25, 0.5),
        Vec2::new(0.75, 0.5),
        Vec2::new(0.5, 1.0),
    ];
    let normals = [
        Vec3::Z,
        Vec3::new(0.0, 1.0, 1.0).normalize(),
        Vec3::new(1.0, 0.0, 1.0).normalize(),
    ];
    let cases = [
        ("v", "f 1 2 3", false, false),
        ("v_vt", "f 1/1 2/2 3/3", true, false),
        ("v__vn", "f 1//1 2//2 3//3", false, true),
        ("v_vt_vn", "f 1/1/1 2/2/2 3/3/3", true, true),
    ];
    for (name, face, has_uv, has_normal) in cases {
        dir.write(format!("{name}.obj"), format!("{head}{face}\n"));
        let scene = mesh(dir.path(), &format!("{name}.obj"));
        assert_eq!(scene.world.stats().triangles, 1, "{name}");
        let want_uv = if has_uv { uvs } else { [Vec2::ZERO; 3] };
        assert_eq!(tri_uvs(&scene, 0), want_uv, "{name}");
        let t = scene.world.geometry().triangles[0];
        assert_eq!(t.smooth, has_normal, "{name}: smooth only with vn");
        if has_normal {
            let n = tri_normals(&scene, 0);
            for k in 0..3 {
                assert!(close(n[k], normals[k]), "{name}: normal {k} is {}", n[k]);
            }
        }
    }
}

#[test]
fn faces_with_and_without_vt_in_one_file_keep_their_own_uvs() {
    // Only the first face has texture coordinates; it must keep them (a loader that requires
    // one vt per vertex for the whole model would drop them all).
    let dir = TempDir::new("mixed_vt");
    dir.write(
        "m.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0.1 0.2\nvt 0.3 0.4\nvt 0.5 0.6\n\
         f 1/1 2/2 3/3\nf 2 4 3\nf 2/2 4 3/3\n",
    );
    let scene = mesh(dir.path(), "m.obj");
    assert_eq!(scene.world.stats().triangles, 3);
    let t = [
        Vec2::new(0.1, 0.2),
        Vec2::new(0.3, 0.4),
        Vec2::new(0.5, 0.6),
    ];
    assert_eq!(tri_uvs(&scene, 0), t);
    assert_eq!(tri_uvs(&scene, 1), [Vec2::ZERO; 3]);
    assert_eq!(tri_uvs(&scene, 2), [t[1], Vec2::ZERO, t[2]], "per corner");
}

#[test]
fn faces_without_vn_stay_flat_beside_smooth_faces() {
    // The first face is smooth (vn at every corner); the second has none and the third has
    // vn at only one corner: both must shade flat, i.e. carry zero vertex normals (the
    // integrator then falls back to the geometric normal), while sharing positions.
    let dir = TempDir::new("mixed_vn");
    dir.write(
        "m.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0.6 0.8\nvn 0.6 0 0.8\nvn 0 0 1\n\
         f 1//1 2//2 3//3\nf 2 4 3\nf 2//2 4 3\n",
    );
    let scene = mesh(dir.path(), "m.obj");
    assert_eq!(scene.world.stats().triangles, 3);
    let n = tri_normals(&scene, 0);
    assert!(close(n[0], Vec3::new(0.0, 0.6, 0.8)) && close(n[1], Vec3::new(0.6, 0.0, 0.8)));
    assert!(scene.world.geometry().triangles[0].smooth);
    assert_eq!(tri_normals(&scene, 1), [Vec3::ZERO; 3], "no vn: flat");
    assert_eq!(tri_normals(&scene, 2), [Vec3::ZERO; 3], "partial vn: flat");
    assert_eq!(
        tri_positions(&scene, 2),
        [Vec3::X, Vec3::ONE.with_z(0.0), Vec3::Y]
    );
}

#[test]
fn zero_normals_make_their_face_flat() {
    let dir = TempDir::new("zero_vn");
    dir.write(
        "z.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nvn 0 0 1\nf 1//1 2//1 3//1\n",
    );
    let scene = mesh(dir.path(), "z.obj");
    assert!(!scene.world.geometry().triangles[0].smooth);
}

#[test]
fn groups_and_objects_do_not_split_or_drop_faces() {
    let dir = TempDir::new("groups");
    dir.write(
        "g.obj",
        format!(
            "{}o first\ng a\nf 1 2 3\ng b c\nf 1 3 4\no second\nf 1 4 5\ng\nf 2 3 4 5\n",
            v_lines(&PENTAGON)
        ),
    );
    let scene = mesh(dir.path(), "g.obj");
    assert_eq!(scene.world.stats().triangles, 1 + 1 + 1 + 2);
    assert_eq!(tri_positions(&scene, 2), [p(0), p(3), p(4)]);
    assert_eq!(tri_positions(&scene, 4), [p(1), p(3), p(4)]);
}

const THREE_COLORS: &str = "newmtl red\nKd 1 0 0\n\nnewmtl green\nKd 0 1 0\n\
                            newmtl blue\nKd 0 0 1\nnewmtl unused\nKd 1 1 0\n";

#[test]
fn an_obj_used_twice_is_read_once_and_shares_its_materials() {
    let dir = TempDir::new("obj-twice");
    dir.write("c.mtl", THREE_COLORS);
    dir.write(
        "u.obj",
        format!(
            "mtllib c.mtl\n{}usemtl green\nf 1 2 3\n",
            v_lines(&PENTAGON)
        ),
    );
    let object = |translate: &str| {
        format!("[[objects]]\ntype = \"mesh\"\nfile = \"u.obj\"\ntranslate = {translate}\n")
    };
    let scene = build(dir.path(), &(object("[0, 0, 0]") + &object("[5, 0, 0]")));
    assert_eq!(scene.world.stats().triangles, 2);
    // One scene material for "green", shared by both copies.
    assert_eq!(scene.world.stats().materials, 1);
    let [a, b] = [0, 1].map(|i| scene.world.geometry().triangles[i].material);
    assert_eq!(a, b);
    assert_eq!(tri_diffuse(&scene, 1), Vec3::Y);
    assert_eq!(
        tri_positions(&scene, 1)[0],
        tri_positions(&scene, 0)[0] + Vec3::X * 5.0
    );
}

#[test]
fn usemtl_switches_materials_per_face() {
    let dir = TempDir::new("usemtl");
    dir.write("c.mtl", THREE_COLORS);
    dir.write(
        "u.obj",
        format!(
            "mtllib c.mtl\n{}f 1 2 3\nusemtl green\nf 1 2 3\ng other\nusemtl red\nf 1 2 3 4\n\
             usemtl blue\nf 1 2 3\nusemtl nosuch\nf 1 2 3\nusemtl green\nf 1 2 3\n",
            v_lines(&PENTAGON)
        ),
    );
    let scene = mesh(dir.path(), "u.obj");
    let (red, green, blue, grey) = (Vec3::X, Vec3::Y, Vec3::Z, Vec3::splat(0.8));
    let want = [grey, green, red, red, blue, grey, green];
    assert_eq!(scene.world.stats().triangles, want.len());
    for (i, w) in want.iter().enumerate() {
        assert_eq!(tri_diffuse(&scene, i), *w, "triangle {i}");
    }
    assert_eq!(
        scene.world.geometry().triangles[0].material,
        0,
        "faces before usemtl use the default material"
    );
    // Only used materials become scene materials: green, red, blue (not "unused").
    assert_eq!(scene.world.stats().materials, 3);
}

#[test]
fn mtl_colors_shininess_and_texture() {
    let dir = TempDir::new("mtl");
    dir.png("tex.png", 3, 2, |_, _| [255, 0, 0]);
    dir.write(
        "m.mtl",
        "# a comment\nnewmtl full\n  Ka 0.1 0.2 0.3\n  Kd 0.4 0.5 0.6 # inline comment\n\
         \tKs 0.7 0.8 0.9\n  Ns 42\n  map_Kd tex.png\n\
         newmtl grey\nKd 0.5\nKs 0.25\n",
    );
    dir.write(
        "m.obj",
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl full\nf 1 2 3\nusemtl grey\nf 1 2 3\n",
    );
    let scene = mesh(dir.path(), "m.obj");
    let m = &scene.world.materials()[scene.world.geometry().triangles[0].material as usize];
    assert_eq!(m.ambient, Vec3::new(0.1, 0.2, 0.3));
    assert_eq!(m.diffuse, Vec3::new(0.4, 0.5, 0.6));
    assert_eq!(m.specular, Vec3::new(0.7, 0.8, 0.9));
    assert_eq!(m.shininess, 42.0);
    let tex = &scene.world.textures()[m.texture.expect("map_Kd gives a texture") as usize];
    match &tex.kind {
        TextureKind::Image(img) => assert_eq!((img.image.width, img.image.height), (3, 2)),
        other => panic!("not an image texture: {other:?}"),
    }
    // One number means grey; Ka defaults to Kd.
    let g = &scene.world.materials()[scene.world.geometry().triangles[1].material as usize];
    assert_eq!(g.diffuse, Vec3::splat(0.5));
    assert_eq!(g.ambient, Vec3::splat(0.5));
    assert_eq!(g.specular, Vec3::splat(0.25));
    assert_eq!(g.texture, None);
}

#[test]
fn mtllib_in_a_subfolder_resolves_map_kd_against_the_mtl_folder() {
    let dir = TempDir::new("subfolder");
    // A decoy of the same name next to the OBJ: the MTL's own folder must win.
    dir.png("tex.png", 1, 1, |_, _| [0, 0, 255]);
    dir.png("sub/tex.png", 5, 4, |_, _| [0, 255, 0]);
    dir.png("sub/maps/with space.png", 7, 1, |_, _| [0, 255, 0]);
    dir.write(
        "sub/x.mtl",
        "newmtl a\nmap_Kd tex.png\nnewmtl b\nmap_Kd -s 2 2 1 -clamp on -mm 0 1 maps/with space.png\n",
    );
    // (In the OBJ's folder or below: a model reads nothing outside it, see tests/reach.rs.)
    dir.write(
        "m.obj",
        "mtllib sub/x.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 2 3\n",
    );
    let scene = mesh(dir.path(), "m.obj");
    let size = |i: usize| {
        let m = &scene.world.materials()[scene.world.geometry().triangles[i].material as usize];
        match &scene.world.textures()[m.texture.unwrap() as usize].kind {
            TextureKind::Image(img) => (img.image.width, img.image.height),
            other => panic!("not an image texture: {other:?}"),
        }
    };
    assert_eq!(size(0), (5, 4));
    assert_eq!(size(1), (7, 1), "options skipped, spaces kept in the name");

    // The brief's layout: `mtllib sub/x.mtl` next to the OBJ.
    dir.write(
        "top.obj",
        "mtllib sub/x.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
    );
    let scene = mesh(dir.path(), "top.obj");
    let m = &scene.world.materials()[scene.world.geometry().triangles[0].material as usize];
    match &scene.world.textures()[m.texture.unwrap() as usize].kind {
        TextureKind::Image(img) => assert_eq!(img.image.width, 5),
        other => panic!("not an image texture: {other:?}"),
    }
}

#[test]
fn scene_material_overrides_the_mtl() {
    let dir = TempDir::new("override");
    dir.write("c.mtl", THREE_COLORS);
    dir.write(
        "o.obj",
        "mtllib c.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\nusemtl blue\nf 1 2 3\nf 1 2 3\n",
    );
    let scene = build(
        dir.path(),
        "[materials.mine]\ndiffuse = [0.2, 0.3, 0.4]\n\n\
         [[objects]]\ntype = \"mesh\"\nfile = \"o.obj\"\nmaterial = \"mine\"\n",
    );
    assert_eq!(scene.world.stats().triangles, 3);
    for (i, t) in scene.world.geometry().triangles.iter().enumerate() {
        assert_eq!(t.material, 1, "triangle {i} uses the scene's material");
    }
    assert_eq!(scene.world.stats().materials, 1, "no MTL material is added");
    assert_eq!(tri_diffuse(&scene, 0), Vec3::new(0.2, 0.3, 0.4));
}

#[test]
fn unused_statements_are_ignored() {
    let dir = TempDir::new("unused");
    dir.write(
        "u.mtl",
        "newmtl m\nNs 10\nNi 1.5\nd 1\nTr 0\nTf 1 1 1\nillum 2\nKe 17 12 4\nKd 0.5 0.25 1\n\
         map_Bump bump.png\nmap_Ks spec.png\nbump b.png\nrefl -type sphere r.png\nsharpness 60\n",
    );
    dir.write(
        "u.obj",
        "# header\nmtllib u.mtl\no thing\ns 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvp 0.5\n\
         cstype bspline\ndeg 3\ng a\nusemtl m\ns off\nl 1 2\np 1\nf 1 2 3\nmg 1\n",
    );
    let scene = mesh(dir.path(), "u.obj");
    assert_eq!(scene.world.stats().triangles, 1);
    assert_eq!(tri_diffuse(&scene, 0), Vec3::new(0.5, 0.25, 1.0));
    assert_eq!(scene.world.materials()[1].shininess, 10.0);
    assert_eq!(
        scene.world.materials()[1].texture,
        None,
        "only map_Kd is a texture"
    );
}

#[test]
fn crlf_tabs_comments_and_continuations() {
    let dir = TempDir::new("crlf");
    dir.write("c.mtl", "\u{feff}newmtl  m \r\n\tKd\t0.5\t0.5\t0.5  \r\n");
    let mut obj = b"\xef\xbb\xbf# caf\xe9 (not UTF-8)\r\nmtllib c.mtl\r\n".to_vec();
    obj.extend_from_slice(
        b"v\t0 0 0 \r\nv  1\t0 0\t\r\nv 0 1 \\\r\n 0\r\n\r\n  usemtl m \r\n\tf\t1 2 3 # tail\r\nf 1 \\\r\n2 3",
    );
    dir.write("c.obj", obj);
    let scene = mesh(dir.path(), "c.obj");
    assert_eq!(
        scene.world.stats().triangles,
        2,
        "the last line has no newline"
    );
    assert_eq!(tri_positions(&scene, 0), [Vec3::ZERO, Vec3::X, Vec3::Y]);
    assert_eq!(
        tri_diffuse(&scene, 0),
        Vec3::splat(0.5),
        "trimmed material name"
    );
}

#[test]
fn index_out_of_range_is_an_error_naming_the_obj_file_and_line() {
    let dir = TempDir::new("range");
    let cases = [
        ("v.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n", "line 5"),
        ("neg.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n", "line 3"),
        (
            "vt.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
            "line 5",
        ),
        (
            "vtneg.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-5 2/-5 3/-5\n",
            "line 5",
        ),
        (
            "vn.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n",
            "line 4",
        ),
        ("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4"),
        (
            "huge.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n",
            "line 4",
        ),
    ];
    for (name, text, line) in cases {
        dir.write(name, text);
        let e = mesh_error(dir.path(), name);
        assert!(e.contains(name), "{name}: {e}");
        assert!(e.contains(line), "{name}: {e}");
        assert!(e.contains("x.toml"), "the scene file too: {e}");
    }
}

#[test]
fn malformed_statements_are_errors_not_panics() {
    let dir = TempDir::new("malformed");
    let cases = [
        ("short.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "at least 3"),
        ("vnum.obj", "v 0 zero 0\n", "line 1"),
        ("vnan.obj", "v 0 NaN 0\n", "finite"),
        (
            "corner.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n",
            "line 4",
        ),
        ("word.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf a b c\n", "line 4"),
    ];
    for (name, text, what) in cases {
        dir.write(name, text);
        let e = mesh_error(dir.path(), name);
        assert!(e.contains(name) && e.contains(what), "{name}: {e}");
    }
    dir.write("bad.mtl", "newmtl m\nKd 0.5 red 0.5\n");
    dir.write("badmtl.obj", "mtllib bad.mtl\n");
    let e = mesh_error(dir.path(), "badmtl.obj");
    assert!(e.contains("bad.mtl") && e.contains("line 2"), "{e}");
}

#[test]
fn missing_files_are_errors_naming_them() {
    let dir = TempDir::new("missing");
    let e = mesh_error(dir.path(), "nothing.obj");
    assert!(e.contains("nothing.obj"), "{e}");

    dir.write(
        "a.obj",
        "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let e = mesh_error(dir.path(), "a.obj");
    assert!(e.contains("gone.mtl") && e.contains("a.obj"), "{e}");

    dir.write("t.mtl", "newmtl m\nmap_Kd textures/gone.png\n");
    dir.write(
        "b.obj",
        "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n",
    );
    let e = mesh_error(dir.path(), "b.obj");
    assert!(e.contains("gone.png"), "{e}");

    // A corrupt texture too.
    dir.write("c.mtl", "newmtl m\nmap_Kd junk.png\n");
    dir.write("junk.png", "not a png");
    dir.write(
        "c.obj",
        "mtllib c.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n",
    );
    let e = mesh_error(dir.path(), "c.obj");
    assert!(e.contains("junk.png"), "{e}");
}

#[test]
fn unused_material_with_a_missing_texture_is_not_an_error() {
    let dir = TempDir::new("unused_tex");
    dir.write(
        "u.mtl",
        "newmtl used\nKd 1 0 0\nnewmtl spare\nmap_Kd gone.png\n",
    );
    dir.write(
        "u.obj",
        "mtllib u.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl used\nf 1 2 3\n",
    );
    let scene = mesh(dir.path(), "u.obj");
    assert_eq!(scene.world.stats().materials, 1);
    assert_eq!(scene.world.stats().textures, 0);
}

#[test]
fn map_kd_with_windows_separators() {
    let dir = TempDir::new("backslash");
    dir.png("maps/t.png", 2, 2, |_, _| [9, 9, 9]);
    dir.write("w.mtl", "newmtl m\nmap_Kd maps\\t.png\n");
    dir.write(
        "w.obj",
        "mtllib w.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n",
    );
    let scene = mesh(dir.path(), "w.obj");
    assert_eq!(scene.world.stats().textures, 1);
}

#[test]
fn an_obj_without_faces_is_an_error() {
    // Nothing in it can be rendered: most likely the wrong file, so it is not an empty mesh.
    let dir = TempDir::new("empty");
    dir.write("e.obj", "# nothing\nv 0 0 0\n");
    let text = "[[objects]]\ntype = \"mesh\"\nfile = \"e.obj\"\n";
    let err = try_build(dir.path(), text).expect_err("an OBJ without faces was accepted");
    assert!(err.to_string().contains("no faces"), "{err}");
}

#[test]
fn normals_use_the_inverse_transpose_under_non_uniform_scale() {
    let dir = TempDir::new("scale");
    // A triangle in the plane x + y = 0 with its normal (1, 1, 0)/√2 at every corner.
    dir.write(
        "s.obj",
        "v 0 0 0\nv 1 -1 0\nv 0 0 1\nvn 0.70710678 0.70710678 0\nf 1//1 2//1 3//1\n",
    );
    let scene = build(
        dir.path(),
        "[[objects]]\ntype = \"mesh\"\nfile = \"s.obj\"\nscale = [4, 1, 1]\nrotate = [0, 0, 90]\n",
    );
    let [a, b, c] = tri_positions(&scene, 0);
    let geometric = (b - a).cross(c - a).normalize();
    for n in tri_normals(&scene, 0) {
        assert!((n.length() - 1.0).abs() < 1e-5, "unit length: {n}");
        assert!(
            close(n, geometric) || close(n, -geometric),
            "normal {n} stays perpendicular to the scaled surface ({geometric})"
        );
    }
    // Scale x by 4: (1, 1, 0) → (1/4, 1, 0), normalized; then turned 90° about z.
    let scaled = Vec3::new(0.25, 1.0, 0.0).normalize();
    let want = Vec3::new(-scaled.y, scaled.x, 0.0);
    assert!(
        close(tri_normals(&scene, 0)[0], want),
        "{}",
        tri_normals(&scene, 0)[0]
    );
}

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets")
}

#[test]
fn cornell_box_obj() {
    let scene = mesh(&assets(), "scenes/cornell_box/CornellBox-Original.obj");
    assert_eq!(scene.world.stats().triangles, 36);
    // Eight MTL materials, all used; materials by `usemtl`, not by `g`.
    assert_eq!(scene.world.stats().materials, 8);
    let count = |kd: Vec3| {
        (0..scene.world.stats().triangles)
            .filter(|&i| close(tri_diffuse(&scene, i), kd))
            .count()
    };
    assert_eq!(count(Vec3::new(0.63, 0.065, 0.05)), 2, "red left wall");
    assert_eq!(count(Vec3::new(0.14, 0.45, 0.091)), 2, "green right wall");
    assert_eq!(count(Vec3::splat(0.78)), 2, "light quad");
    // Floor, ceiling, back wall and the two boxes (6 faces each, bottoms included).
    assert_eq!(count(Vec3::new(0.725, 0.71, 0.68)), 2 + 2 + 2 + 12 + 12);
    let lit = scene
        .world
        .materials()
        .iter()
        .find(|m| m.diffuse == Vec3::splat(0.78))
        .unwrap();
    assert_eq!(lit.ambient, Vec3::splat(0.78));
    assert_eq!(lit.shininess, 10.0);
    assert_eq!(lit.specular, Vec3::ZERO);
    // The floor's quad `f -4 -3 -2 -1` right after its four `v` lines (CRLF, tabs).
    let first = tri_positions(&scene, 0);
    assert!(close(first[0], Vec3::new(-1.01, 0.0, 0.99)), "{first:?}");
    assert!(close(first[2], Vec3::new(1.0, 0.0, -1.04)), "{first:?}");
    let b = scene.world.geometry().bounds();
    assert!(close(b.min, Vec3::new(-1.02, 0.0, -1.04)), "{b:?}");
    assert!(close(b.max, Vec3::new(1.0, 1.99, 0.99)), "{b:?}");
}

#[test]
fn spot_triangulated_and_quadrangulated() {
    for name in ["spot_triangulated.obj", "spot_quadrangulated.obj"] {
        let scene = mesh(&assets(), &format!("meshes/{name}"));
        assert_eq!(scene.world.stats().triangles, 5_856, "{name}");
        let g = scene.world.geometry();
        assert!(g.triangles.iter().all(|t| !t.smooth), "{name}: no vn");
        assert!(
            g.uvs
                .iter()
                .all(|uv| (-0.06..=1.01).contains(&uv.x) && (0.1..=1.01).contains(&uv.y)),
            "{name}: uvs as in the file (u -0.052…0.989, v 0.111…1.0007)"
        );
        // The uv seams: more distinct (v, vt) corners than positions in the file.
        assert!(g.positions.len() > 2_930, "{name}: {}", g.positions.len());
        let b = g.bounds();
        assert!(b.min.y < -0.7 && b.max.y > 0.9, "{name}: {b:?}");
    }
}

#[test]
fn spot_with_an_mtl_gets_its_texture() {
    // The asset has no mtllib: prepend one to a copy, with an MTL naming the real texture.
    let dir = TempDir::new("spot_mtl");
    let original = std::fs::read(assets().join("meshes/spot_triangulated.obj")).unwrap();
    let mut obj = b"mtllib spot.mtl\nusemtl spot\n".to_vec();
    obj.extend_from_slice(&original);
    dir.write("spot.obj", obj);
    // A copy of the texture too: a model reads only in its own folder (see tests/reach.rs).
    let texture = std::fs::read(assets().join("textures/spot_texture.png")).unwrap();
    dir.write("spot_texture.png", texture);
    dir.write(
        "spot.mtl",
        "newmtl spot\nKd 1 1 1\nmap_Kd spot_texture.png\n",
    );
    let scene = mesh(dir.path(), "spot.obj");
    assert_eq!(scene.world.stats().triangles, 5_856);
    assert_eq!(scene.world.stats().textures, 1);
    let m = &scene.world.materials()[scene.world.geometry().triangles[0].material as usize];
    assert!(m.texture.is_some());
    assert!(scene
        .world
        .geometry()
        .triangles
        .iter()
        .all(|t| t.material == scene.world.geometry().triangles[0].material));
}
