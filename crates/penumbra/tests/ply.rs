//! PLY meshes through the public API: `type = "mesh"` and `type = "instances"` scene objects
//! naming `.ply` files written into a temporary folder, their errors at the object's `file`
//! key, and the real files of the shared assets when they are present.

mod support;

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use penumbra::{inspect_ply, AssetKind, ErrorKind, Scene, SceneError, SceneFile, SceneFormat};
use support::TempDir;

const HEAD: &str = "[film]\nwidth = 4\nheight = 4\n[camera]\nposition = [0, 0, 5]\n\
                    look_at = [0, 0, 0]\nfov = 40\n";

fn build(dir: &TempDir, objects: &str) -> Result<Scene, SceneError> {
    let text = format!("{HEAD}{objects}");
    SceneFile::from_str(&text, SceneFormat::Toml, "x.toml", dir.path())?.build(1)
}

/// A unit square in z = 0 as one quad, binary little-endian, with normals and `s`/`t` uvs.
fn square_ply() -> Vec<u8> {
    let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\n\
        property float x\nproperty float y\nproperty float z\nproperty float nx\n\
        property float ny\nproperty float nz\nproperty uchar red\nproperty float s\n\
        property float t\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n"
        .to_vec();
    for [x, y] in [[0.0f32, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]] {
        for v in [x, y, 0.0, 0.0, 0.0, 1.0] {
            bytes.extend(v.to_le_bytes());
        }
        bytes.push(255);
        for v in [x, y] {
            bytes.extend(v.to_le_bytes());
        }
    }
    bytes.push(4);
    for i in 0u32..4 {
        bytes.extend(i.to_le_bytes());
    }
    bytes
}

#[test]
fn a_ply_mesh_loads_as_an_obj_does_whatever_the_case_of_its_extension() {
    let dir = TempDir::new("ply_mesh");
    dir.write("square.PLY", square_ply());
    let scene = build(
        &dir,
        "[[objects]]\ntype = \"mesh\"\nfile = \"square.PLY\"\n",
    )
    .unwrap();
    let g = scene.world.geometry();
    assert_eq!(g.triangles.len(), 2);
    assert_eq!(
        g.corners(1),
        [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y]
    );
    let uvs = g.triangles[1].vertices.map(|v| g.uvs[v as usize]);
    assert_eq!(uvs, [Vec2::ZERO, Vec2::ONE, Vec2::Y]);
    assert!(g.triangles[1].smooth);
}

/// A MeshLab-style textured, coloured square: `comment TextureFile`, byte colours, and a
/// per-face `texcoord` list on each of its two triangles.
const TEXTURED_PLY: &str = "ply\nformat ascii 1.0\ncomment TextureFile tex/red.png\n\
    element vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
    property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n\
    element face 2\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\n\
    end_header\n0 0 0 255 255 255 255\n1 0 0 255 0 0 255\n1 1 0 0 0 255 255\n\
    0 1 0 255 255 255 255\n3 0 1 2 6 0 0 1 0 1 1\n3 0 2 3 6 0.5 0.5 1 1 0 1\n";

#[test]
fn a_textured_coloured_ply_keeps_its_colours_texture_and_texcoords() {
    let dir = TempDir::new("ply_textured");
    dir.write("square.ply", TEXTURED_PLY);
    dir.png("tex/red.png", 2, 2, |_, _| [255, 0, 0]);
    let scene = build(
        &dir,
        "[[objects]]\ntype = \"mesh\"\nfile = \"square.ply\"\n",
    )
    .unwrap();
    let world = &scene.world;
    let g = world.geometry();
    // Vertex 0 has two texcoords (one per face): split in two.
    assert_eq!((g.triangles.len(), g.positions.len()), (2, 5));
    let colors = g.triangles[0].vertices.map(|v| g.colors[v as usize]);
    assert_eq!(colors, [Vec3::ONE, Vec3::X, Vec3::Z]);
    let uvs = g.triangles[1].vertices.map(|v| g.uvs[v as usize]);
    assert_eq!(uvs, [Vec2::splat(0.5), Vec2::ONE, Vec2::Y]);
    let material = &world.materials()[g.triangles[0].material as usize];
    assert_eq!(material.texture, Some(0));
    assert_eq!(world.textures().len(), 1);
    assert!(
        scene.files.iter().any(|f| f.ends_with("tex/red.png")),
        "{:?}",
        scene.files
    );
    let info = inspect_ply(&dir.join("square.ply")).unwrap();
    assert!(info.colors && info.uvs);
    assert_eq!(info.materials.len(), 1);
    assert_eq!(
        info.warnings,
        [
            "element `vertex`: property `alpha` is read but ignored (penumbra has no vertex \
          transparency)"
        ]
    );
    // A texture that is there but broken is an image error naming it.
    std::fs::write(dir.join("tex/red.png"), b"not a png").unwrap();
    let e = build(
        &dir,
        "[[objects]]\ntype = \"mesh\"\nfile = \"square.ply\"\n",
    )
    .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Asset(AssetKind::Image), "{e}");
    assert!(e.to_string().contains("red.png"), "{e}");
    // A missing one is dropped with a warning naming it (as trimesh and MeshLab read it).
    std::fs::remove_file(dir.join("tex/red.png")).unwrap();
    let scene = build(
        &dir,
        "[[objects]]\ntype = \"mesh\"\nfile = \"square.ply\"\n",
    )
    .unwrap();
    assert!(scene.world.textures().is_empty());
    assert!(
        scene.warnings.iter().any(|w| w.contains("red.png")),
        "{:?}",
        scene.warnings
    );
}

#[test]
fn ply_files_are_read_once_and_instanced_by_the_copy_or_instance_rule() {
    let dir = TempDir::new("ply_instances");
    dir.write("square.ply", square_ply());
    let copies = |n: usize| {
        let list: Vec<String> = (0..n)
            .map(|i| format!("{{ translate = [{}, 0, 0] }}", i as f32 * 0.01))
            .collect();
        format!(
            "[[objects]]\ntype = \"instances\"\nfile = \"square.ply\"\ntransforms = [{}]\n\
             [[objects]]\ntype = \"mesh\"\nfile = \"./square.ply\"\n",
            list.join(", ")
        )
    };
    let s = build(&dir, &copies(3)).unwrap().world.stats();
    assert_eq!((s.triangles, s.unique_triangles, s.instances), (8, 8, 0));
    // 2^20 / 2 copies and more: built once, shared by both objects (one file, two spellings).
    let n = (1 << 20) / 2 + 1;
    let s = build(&dir, &copies(n)).unwrap().world.stats();
    assert_eq!(s.triangles, 2 * (n + 1));
    assert_eq!((s.unique_triangles, s.meshes, s.instances), (2, 1, n + 1));
}

#[test]
fn a_bad_ply_file_is_a_mesh_error_at_the_file_key() {
    let dir = TempDir::new("ply_bad");
    let mut truncated = square_ply();
    truncated.truncate(truncated.len() - 3);
    let cases: [(&[u8], &str); 3] = [
        (&truncated, "ends early"),
        (b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n", "no triangles"),
        (b"solid stl\n", "not a PLY file"),
    ];
    for (bytes, words) in cases {
        dir.write("bad.ply", bytes);
        let e = build(&dir, "[[objects]]\ntype = \"mesh\"\nfile = \"bad.ply\"\n").unwrap_err();
        let SceneError::Invalid {
            kind,
            location,
            message,
        } = &e
        else {
            panic!("{e}");
        };
        assert_eq!(*kind, ErrorKind::Asset(AssetKind::Mesh), "{e}");
        assert_eq!(location.key.as_deref(), Some("objects[0].file"), "{e}");
        assert!(
            message.contains("bad.ply") && message.contains(words),
            "{e}"
        );
    }
    let e = build(
        &dir,
        "[[objects]]\ntype = \"mesh\"\nfile = \"missing.ply\"\n",
    )
    .unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Asset(AssetKind::Mesh), "{e}");
}

/// A file of the shared assets (`../shared/assets/ply/` beside the repository), or `None`
/// with a message when this machine lacks it.
fn shared(name: &str) -> Option<PathBuf> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/assets/ply")
        .join(name);
    if !path.is_file() {
        eprintln!("skipped: {} is absent", path.display());
        return None;
    }
    Some(path)
}

#[test]
fn the_shared_ply_files_have_their_triangles_and_bounds() {
    if let Some(path) = shared("bunny_zipper.ply") {
        let info = inspect_ply(&path).unwrap();
        assert_eq!((info.triangles, info.vertices), (16_301, 8_171));
        assert!(!info.normals && !info.uvs);
        let (min, max) = (info.bounds.min, info.bounds.max);
        assert!(
            min.abs_diff_eq(Vec3::new(-0.0945716, 0.0333891, -0.0618736), 1e-7),
            "{min}"
        );
        assert!(
            max.abs_diff_eq(Vec3::new(0.0609346, 0.186643, 0.0586895), 1e-7),
            "{max}"
        );
    }
    if let Some(path) = shared("cube_blender_uv.ply") {
        let info = inspect_ply(&path).unwrap();
        assert_eq!((info.triangles, info.vertices), (12, 24));
        assert!(info.normals && info.uvs);
        assert_eq!(
            (info.bounds.min, info.bounds.max),
            (Vec3::splat(-0.5), Vec3::splat(0.5))
        );
        assert!(info.closed);
    }
}

/// A VCGlib ASCII PLY (as MeshLab's "Save As" writes one with face flags): each face line
/// ends with values its header does not declare.
const VCGLIB_ASCII: &str = "ply\nformat ascii 1.0\ncomment VCGLIB generated\n\
    comment TextureFile absent_texture.png\nelement vertex 4\nproperty float x\n\
    property float y\nproperty float z\nproperty float s\nproperty float t\nelement face 2\n\
    property list uchar int vertex_indices\nend_header\n\
    0 0 0 0 0 \n1 0 0 1 0 \n1 1 0 1 1 \n0 1 0 0 1 \n3 0 1 2 0 0 0 \n3 0 2 3 0 0 0 \n";

#[test]
fn a_vcglib_ascii_file_with_extra_face_values_and_a_missing_texture_file_loads() {
    let dir = TempDir::new("ply_vcglib");
    dir.write("vcg.ply", VCGLIB_ASCII);
    let scene = build(&dir, "[[objects]]\ntype = \"mesh\"\nfile = \"vcg.ply\"\n").unwrap();
    let g = scene.world.geometry();
    // Both faces: the extra values at the ends of the lines are not the next face's.
    assert_eq!(g.triangles.len(), 2);
    assert_eq!(
        g.corners(1),
        [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y]
    );
    let warned = |what: &str| scene.warnings.iter().any(|w| w.contains(what));
    assert!(
        warned("6 value(s) at the ends of 2 `face` row(s)") && warned("vcg.ply"),
        "{:?}",
        scene.warnings
    );
    assert!(
        warned("absent_texture.png") && warned("read without it"),
        "{:?}",
        scene.warnings
    );
    // inspect_ply says the same.
    let info = inspect_ply(&dir.join("vcg.ply")).unwrap();
    assert_eq!(info.triangles, 2);
    assert!(info
        .warnings
        .iter()
        .any(|w| w.contains("absent_texture.png")));
    // With the texture there, it is used.
    dir.png("absent_texture.png", 2, 2, |_, _| [255, 0, 0]);
    let scene = build(&dir, "[[objects]]\ntype = \"mesh\"\nfile = \"vcg.ply\"\n").unwrap();
    assert!(!scene.warnings.iter().any(|w| w.contains("absent_texture")));
    assert_eq!(scene.world.textures().len(), 1);
}
