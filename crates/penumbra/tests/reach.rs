//! What a file may read (see the module `reach`): a scene file reads only files in its own
//! folder and below, a model (OBJ and its MTL, PLY, glTF) only in its own folder and below,
//! and the folders allowed besides widen both. Absolute paths, `..` (also percent-encoded in a
//! glTF URI) and symbolic links out are refused, naming the file, the reference and the rule.

mod support;

use std::path::{Path, PathBuf};

use penumbra::{ErrorKind, SceneFile};
use support::{line_of, with_mesh, with_texture, TempDir, BASE_TOML};

/// Builds the scene at `path`, its files also reading in `allowed`; the error's text.
fn build(path: &Path, allowed: &[&Path]) -> Result<(), String> {
    let allowed = allowed.iter().map(|p| p.to_path_buf()).collect();
    SceneFile::load_allowing(path, &[], allowed)
        .and_then(|file| file.build(1))
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn assert_refused(result: Result<(), String>, wants: &[&str]) {
    let e = result.expect_err("read a file outside its folder");
    for want in wants {
        assert!(e.contains(want), "{want:?} not in: {e}");
    }
    assert!(e.contains("--allow-path DIR"), "the rule is named: {e}");
}

const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n";

#[test]
fn a_scene_reads_only_in_its_folder_unless_a_folder_is_allowed() {
    let dir = TempDir::new("reach-scene");
    dir.write("secret/tri.obj", TRIANGLE);
    dir.png("secret/wood.png", 2, 2, |_, _| [9, 9, 9]);
    dir.write("scenes/ok/tri.obj", TRIANGLE);
    let secret = dir.join("secret");
    let absolute = secret.join("tri.obj").display().to_string();
    for (i, reference) in [
        "../secret/tri.obj",
        absolute.as_str(),
        "ok/../../secret/tri.obj",
    ]
    .into_iter()
    .enumerate()
    {
        let text = with_mesh(reference);
        let path = dir.write(format!("scenes/mesh{i}.toml"), &text);
        let line = line_of(&text, "file = ");
        let at = format!("mesh{i}.toml:{line}:1: objects[2].file: \"{reference}\"");
        assert_refused(
            build(&path, &[]),
            &[&at, "is outside the scene's folder", "scenes/ ("],
        );
        build(&path, &[&secret]).unwrap();
    }
    let inside = dir.write("scenes/inside.toml", with_mesh("ok/tri.obj"));
    build(&inside, &[]).unwrap();

    let texture = dir.write("scenes/texture.toml", with_texture("../secret/wood.png"));
    assert_refused(
        build(&texture, &[]),
        &["textures.wood.file: \"../secret/wood.png\""],
    );
    build(&texture, &[&secret]).unwrap();
    let environment =
        format!("{BASE_TOML}\n[[lights]]\ntype = \"environment\"\nfile = \"../secret/wood.png\"\n");
    let environment = dir.write("scenes/environment.toml", environment);
    assert_refused(build(&environment, &[]), &["lights[1].file"]);
    build(&environment, &[&secret]).unwrap();
}

#[test]
fn transforms_and_the_output_stay_in_the_scene_folder_too() {
    let dir = TempDir::new("reach-npy");
    dir.write("scenes/tri.obj", TRIANGLE);
    let identity: Vec<u8> = [
        1f32, 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1.,
    ]
    .iter()
    .flat_map(|x| x.to_le_bytes())
    .collect();
    dir.write("data/t.npy", support::npy("<f4", "(1, 4, 4)", &identity));
    let instances = format!(
        "{BASE_TOML}\n[[objects]]\ntype = \"instances\"\nfile = \"tri.obj\"\n\
         transforms = \"../data/t.npy\"\n"
    );
    let path = dir.write("scenes/instances.toml", instances);
    assert_refused(
        build(&path, &[]),
        &["objects[2].transforms: \"../data/t.npy\""],
    );
    build(&path, &[&dir.join("data")]).unwrap();

    let output = BASE_TOML.replace("height = 12\n", "height = 12\noutput = \"../out/x.png\"\n");
    let path = dir.write("scenes/output.toml", &output);
    assert_refused(build(&path, &[]), &["film.output: \"../out/x.png\""]);
    // A folder not made yet, checked by the part that exists.
    build(&path, &[&dir.join("out")]).unwrap();
    let below = output.replace("../out/x.png", "renders/new/x.png");
    let path = dir.write("scenes/below.toml", below);
    build(&path, &[]).unwrap();
}

#[test]
fn an_obj_reads_its_libraries_and_textures_only_in_its_folder() {
    let dir = TempDir::new("reach-obj");
    dir.png("shared/t.png", 2, 2, |_, _| [9, 9, 9]);
    dir.write("shared/lib.mtl", "newmtl m\nKd 1 1 1\n");
    dir.write("model/maps.mtl", "newmtl m\nmap_Kd ../shared/t.png\n");
    dir.write(
        "model/a.obj",
        format!("mtllib ../shared/lib.mtl\n{TRIANGLE}"),
    );
    dir.write(
        "model/b.obj",
        format!("mtllib maps.mtl\nusemtl m\n{TRIANGLE}"),
    );
    let a = dir.write("model/a.toml", with_mesh("a.obj"));
    assert_refused(
        build(&a, &[]),
        &["`mtllib` \"../shared/lib.mtl\" is outside the model's folder"],
    );
    let b = dir.write("model/b.toml", with_mesh("b.obj"));
    assert_refused(
        build(&b, &[]),
        &["line 2: `map_Kd` \"../shared/t.png\" is outside the model's folder"],
    );
    let shared = dir.join("shared");
    build(&a, &[&shared]).unwrap();
    build(&b, &[&shared]).unwrap();
    // Rendered on its own, the model's folder is its root as well.
    assert_refused(build(&dir.join("model/b.obj"), &[]), &["`map_Kd`"]);
    build(&dir.join("model/b.obj"), &[&shared]).unwrap();
}

#[test]
fn a_model_placed_by_a_scene_reads_in_its_own_folder() {
    // The scene allows the models' folder; what the model names is then relative to, and
    // held to, the model's folder, not the scene's.
    let dir = TempDir::new("reach-model-root");
    dir.png("models/maps/t.png", 2, 2, |_, _| [9, 9, 9]);
    dir.write("models/m.mtl", "newmtl m\nmap_Kd maps/t.png\n");
    dir.write(
        "models/m.obj",
        format!("mtllib m.mtl\nusemtl m\n{TRIANGLE}"),
    );
    let path = dir.write("scenes/s.toml", with_mesh("../models/m.obj"));
    build(&path, &[&dir.join("models")]).unwrap();
    assert_refused(build(&path, &[]), &["objects[2].file: \"../models/m.obj\""]);
}

#[test]
fn a_ply_texture_file_stays_in_its_folder() {
    let dir = TempDir::new("reach-ply");
    dir.png("shared/t.png", 2, 2, |_, _| [9, 9, 9]);
    let ply = "ply\nformat ascii 1.0\ncomment TextureFile ../shared/t.png\nelement vertex 3\n\
               property float x\nproperty float y\nproperty float z\nproperty float u\n\
               property float v\nelement face 1\nproperty list uchar int vertex_indices\n\
               end_header\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n";
    dir.write("model/m.ply", ply);
    let path = dir.write("model/s.toml", with_mesh("m.ply"));
    assert_refused(
        build(&path, &[]),
        &["`comment TextureFile` \"../shared/t.png\" is outside the model's folder"],
    );
    build(&path, &[&dir.join("shared")]).unwrap();
}

/// A glTF file of one triangle whose buffer is `buffer` and whose material's base colour
/// is the image `image`.
fn gltf(buffer: &str, image: &str) -> String {
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "material": 0}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}}}}}],
  "textures": [{{"source": 0}}],
  "images": [{{"uri": "{image}"}}],
  "buffers": [{{"uri": "{buffer}", "byteLength": 60}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 24}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}}]}}"#
    )
}

fn triangle_bin() -> Vec<u8> {
    [0f32, 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 1.]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect()
}

#[test]
fn a_gltf_reads_its_buffers_and_images_only_in_its_folder() {
    let dir = TempDir::new("reach-gltf");
    dir.write("model/tri.bin", triangle_bin());
    dir.write("secret/tri.bin", triangle_bin());
    dir.png("model/t.png", 2, 2, |_, _| [9, 9, 9]);
    dir.png("secret/t.png", 2, 2, |_, _| [9, 9, 9]);
    let secret = dir.join("secret");
    let absolute = secret.join("tri.bin").display().to_string();
    let cases = [
        (
            "../secret/tri.bin",
            "t.png",
            "buffers[0].uri: \"../secret/tri.bin\"",
        ),
        (
            "%2e%2e/secret/tri.bin",
            "t.png",
            "buffers[0].uri: \"../secret/tri.bin\"",
        ),
        ("%2E%2E%2Fsecret%2Ftri.bin", "t.png", "buffers[0].uri"),
        (absolute.as_str(), "t.png", "buffers[0].uri"),
        (
            "tri.bin",
            "../secret/t.png",
            "images[0].uri: \"../secret/t.png\"",
        ),
    ];
    for (i, (buffer, image, want)) in cases.into_iter().enumerate() {
        let model = dir.write(format!("model/m{i}.gltf"), gltf(buffer, image));
        let scene = dir.write(format!("model/s{i}.toml"), with_mesh(&format!("m{i}.gltf")));
        assert_refused(build(&scene, &[]), &[want, "is outside the model's folder"]);
        assert_refused(build(&model, &[]), &[want]);
        build(&scene, &[&secret]).unwrap();
        build(&model, &[&secret]).unwrap();
    }
    let fine = dir.write("model/fine.gltf", gltf("tri.bin", "t.png"));
    build(&fine, &[]).unwrap();
}

#[cfg(unix)]
#[test]
fn a_symbolic_link_out_of_the_folder_is_refused() {
    let dir = TempDir::new("reach-link");
    dir.write("secret/tri.bin", triangle_bin());
    dir.png("model/t.png", 2, 2, |_, _| [9, 9, 9]);
    std::fs::create_dir_all(dir.join("model")).unwrap();
    std::os::unix::fs::symlink(dir.join("secret/tri.bin"), dir.join("model/tri.bin")).unwrap();
    std::os::unix::fs::symlink(dir.join("secret"), dir.join("model/inner")).unwrap();
    for (i, buffer) in ["tri.bin", "inner/tri.bin"].into_iter().enumerate() {
        let model = dir.write(format!("model/m{i}.gltf"), gltf(buffer, "t.png"));
        assert_refused(
            build(&model, &[]),
            &["buffers[0].uri", "outside the model's folder"],
        );
        build(&model, &[&dir.join("secret")]).unwrap();
    }
    // A link to the scene's own folder is inside it.
    dir.write("scenes/tri.obj", TRIANGLE);
    std::os::unix::fs::symlink(dir.join("scenes"), dir.join("scenes/self")).unwrap();
    let path = dir.write("scenes/s.toml", with_mesh("self/tri.obj"));
    build(&path, &[]).unwrap();
}

#[test]
fn a_refusal_is_an_input_error_naming_the_reference() {
    let dir = TempDir::new("reach-kind");
    dir.write("tri.obj", TRIANGLE);
    let path = dir.write("scenes/s.toml", with_mesh("../tri.obj"));
    let e = SceneFile::load(&path).unwrap().build(1).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Asset(penumbra::AssetKind::Mesh), "{e}");
    let location = e.location().unwrap();
    assert_eq!(location.key.as_deref(), Some("objects[2].file"));
    let scenes: PathBuf = dir.join("scenes");
    let message = e.to_string();
    assert!(
        message.contains(&format!("outside the scene's folder {}/", scenes.display())),
        "{message}"
    );
}
