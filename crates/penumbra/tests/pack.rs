//! Packed scenes: a scene packed with the files its build read builds the same world, and
//! renders the same bytes, where those files do not exist.

mod support;

use std::path::PathBuf;

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
    let file = SceneFile::load(&path).unwrap();
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
    let file = SceneFile::load(&path).unwrap();
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
    let file = SceneFile::load_with(&path, &set).unwrap();
    let scene = file.build(1).unwrap();
    let pack = file.pack(&scene.files).unwrap();
    assert_eq!(pack.overrides, ["film.width=7"]);
    assert_eq!(pack.load().unwrap().build(1).unwrap().settings.width, 7);
}
