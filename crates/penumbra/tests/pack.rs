//! Packed scenes: a scene packed with the files its build read builds the same world, and
//! renders the same bytes, where those files do not exist.

mod support;

use std::path::{Path, PathBuf};

use penumbra::{render, Film, RenderOptions, SceneFile, ScenePack};
use support::{with_mesh, with_texture, TempDir};

/// An OBJ with a material library whose `map_Kd` is a PNG, and a scene-level PNG texture.
fn write_scene(dir: &TempDir) -> PathBuf {
    dir.png("textures/wood.png", 4, 4, |x, y| {
        [40 * x as u8, 50 * y as u8, 90]
    });
    dir.png("meshes/maps/tile.png", 2, 2, |x, _| [200, 30 * x as u8, 10]);
    dir.write(
        "meshes/tri.mtl",
        "newmtl tile\nKd 0.8 0.8 0.8\nmap_Kd maps/tile.png\n",
    );
    dir.write(
        "meshes/tri.obj",
        "mtllib tri.mtl\nv -1 -1 0.5\nv 1 -1 0.5\nv 0 1 0.5\nvt 0 0\nvt 1 0\nvt 0.5 1\n\
         usemtl tile\nf 1/1 2/2 3/3\n",
    );
    // The room's cube textured, and the OBJ as one more object (with its MTL materials).
    let mesh = with_mesh("../meshes/tri.obj").replace(support::BASE_TOML, "");
    let text = with_texture("../textures/wood.png") + &mesh;
    dir.write("scenes/room.toml", text)
}

/// The scene at `path`, whose files may read anywhere in `dir` (it reads `../meshes`), with
/// the overrides `set`.
fn load(dir: &TempDir, path: &Path, set: &[penumbra::Override]) -> SceneFile {
    SceneFile::load_allowing(path, set, vec![dir.path().to_owned()]).unwrap()
}

fn small(file: &SceneFile) -> Film {
    let scene = file.build(1).unwrap();
    let mut settings = scene.settings.clone();
    settings.width = 24;
    settings.height = 16;
    render(&scene.world, &settings, &RenderOptions::default())
        .unwrap()
        .0
}

#[test]
fn a_pack_builds_the_same_scene_without_the_files_on_disk() {
    let dir = TempDir::new("pack");
    let path = write_scene(&dir);
    let file = load(&dir, &path, &[]);
    let scene = file.build(0).unwrap();
    let scenes = dir.join("scenes");
    let expected: Vec<PathBuf> = [
        "../meshes/tri.mtl",
        "../meshes/tri.obj",
        "../textures/wood.png",
    ]
    .iter()
    .map(|p| scenes.join(p))
    .chain([scenes.join("../meshes/maps/tile.png")])
    .collect();
    let mut listed = scene.files.clone();
    listed.sort();
    let mut want = expected.clone();
    want.sort();
    assert_eq!(listed, want, "the files the build read");

    let pack = file.pack(&scene.files).unwrap();
    assert_eq!(pack.files.len(), 4);
    assert_eq!(
        pack.allowed,
        [dir.path()],
        "the folders allowed travel with the pack"
    );
    assert_eq!(
        pack.file_bytes() as u64,
        want.iter()
            .map(|p| std::fs::metadata(p).unwrap().len())
            .sum::<u64>()
    );
    let original = small(&file);
    drop(dir);
    assert!(!path.exists());

    let unpacked = pack.clone().load().unwrap();
    assert!(unpacked.files().is_packed());
    assert_eq!(small(&unpacked), original, "same bytes from the pack");
    let rebuilt = unpacked.build(2).unwrap();
    assert_eq!(rebuilt.files, scene.files);
    assert_eq!(
        rebuilt.world.stats().triangles,
        scene.world.stats().triangles
    );
    // Packing a packed scene gives the same pack.
    assert_eq!(unpacked.pack(&rebuilt.files).unwrap(), pack);
}

#[test]
fn a_pack_missing_a_file_fails_as_a_missing_file_does() {
    let dir = TempDir::new("pack-missing");
    let path = write_scene(&dir);
    let file = load(&dir, &path, &[]);
    let scene = file.build(1).unwrap();
    let mut pack: ScenePack = file.pack(&scene.files).unwrap();
    let obj = dir.join("scenes/../meshes/tri.obj");
    assert!(pack.files.remove(&obj).is_some());
    let e = pack.load().unwrap().build(1).unwrap_err().to_string();
    assert!(
        e.contains("tri.obj") && e.contains("not in the scene's packed files"),
        "{e}"
    );
}

#[test]
fn overrides_travel_with_the_pack() {
    let dir = TempDir::new("pack-overrides");
    let path = write_scene(&dir);
    let set = [penumbra::Override::parse("film.width=7").unwrap()];
    let file = load(&dir, &path, &set);
    let scene = file.build(1).unwrap();
    let pack = file.pack(&scene.files).unwrap();
    assert_eq!(pack.overrides, ["film.width=7"]);
    assert_eq!(pack.load().unwrap().build(1).unwrap().settings.width, 7);
}

#[test]
fn a_scene_keeping_its_files_packs_the_bytes_its_build_read() {
    let dir = TempDir::new("pack-snapshot");
    let path = write_scene(&dir);
    let file = load(&dir, &path, &[]).keeping_files();
    let scene = file.build(1).unwrap();
    let original = small(&file);
    let obj = dir.join("scenes/../meshes/tri.obj");
    let read = std::fs::read(&obj).unwrap();
    // The mesh edited on disk after the build: two triangles, elsewhere.
    dir.write(
        "meshes/tri.obj",
        "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nv 2 2 0\nf 1 2 3\nf 2 4 3\n",
    );
    let pack = file.pack(&scene.files).unwrap();
    assert_eq!(pack.files[&obj], read, "the pack holds what the build read");
    let unpacked = pack.load().unwrap();
    let rebuilt = unpacked.build(1).unwrap();
    assert_eq!(
        rebuilt.world.stats().triangles,
        scene.world.stats().triangles
    );
    assert_eq!(
        small(&unpacked),
        original,
        "the pack renders the scene as loaded"
    );
    // A file read without keeping is read again: the edited mesh.
    let plain = load(&dir, &path, &[]);
    let now = plain.pack(&scene.files).unwrap();
    assert_ne!(now.files[&obj], read);
}

#[test]
fn a_pack_with_a_bad_override_is_a_scene_error_naming_it() {
    let dir = TempDir::new("pack-bad-override");
    let path = write_scene(&dir);
    let file = load(&dir, &path, &[]);
    let scene = file.build(1).unwrap();
    for (bad, why) in [
        ("film.width", "no `=`"),
        ("=3", "an empty key"),
        ("\"film.width=3", "an unclosed quote"),
    ] {
        let mut pack = file.pack(&scene.files).unwrap();
        pack.overrides = vec!["film.height=5".to_owned(), bad.to_owned()];
        let e = pack.load().unwrap_err();
        assert_eq!(e.kind(), penumbra::ErrorKind::Syntax, "{bad}: {e}");
        let location = e.location().expect("located");
        assert_eq!(location.set_by.as_deref(), Some(bad));
        let message = e.to_string();
        assert!(
            message.contains(why) && message.contains("room.toml") && !message.contains('\n'),
            "{bad}: {message}"
        );
    }
}

#[test]
fn a_pack_keeps_the_rule_on_the_paths_it_names() {
    let dir = TempDir::new("pack-rule");
    let path = write_scene(&dir);
    let file = load(&dir, &path, &[]);
    let scene = file.build(1).unwrap();
    let mut pack = file.pack(&scene.files).unwrap();
    pack.allowed.clear();
    let e = pack.load().unwrap().build(1).unwrap_err().to_string();
    assert!(
        e.contains("\"../textures/wood.png\" is outside the scene's folder"),
        "{e}"
    );
}
