//! The bodies of penumbra's fuzz targets: each takes the bytes of one input, feeds them to the
//! library's public entry points as a user's file would be, and panics only when the library
//! breaks a promise: a panic of its own, a result that succeeds with non-finite geometry, an
//! invalid BVH or a NaN/Inf pixel, a scene that builds but does not render, or a scene error
//! whose message is not one clean line.
//! Errors are the expected answer to most inputs.
//!
//! The same functions run under cargo-fuzz (the `fuzz/` crate, nightly) and in the stable
//! regression test (`tests/corpus.rs`), which replays the committed corpus and every crash
//! found so far.
//!
//! Every target bounds its work per input: scenes are built and rendered at 4×4 pixels, one
//! sample per pixel and one light sample, whatever the file asks for.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod formats;

pub use formats::hdr;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use penumbra::{
    decode_texture_image, inspect_gltf_bytes, inspect_mtl, inspect_obj_bytes, inspect_ply_bytes,
    render, Aabb, Light, Override, RenderOptions, RenderSettings, SceneError, SceneFile,
    SceneFormat, ScenePack, World,
};

/// A fuzz target: its name (the folder of its corpus) and its body.
pub struct Target {
    /// The name cargo-fuzz knows it by.
    pub name: &'static str,
    /// Runs one input; panics when the library misbehaves.
    pub run: fn(&[u8]),
}

/// Every target.
pub const TARGETS: [Target; 10] = [
    Target {
        name: "scene_toml",
        run: scene_toml,
    },
    Target {
        name: "scene_json",
        run: scene_json,
    },
    Target {
        name: "scene_override",
        run: scene_override,
    },
    Target {
        name: "obj",
        run: obj,
    },
    Target {
        name: "mtl",
        run: mtl,
    },
    Target {
        name: "ply",
        run: ply,
    },
    Target {
        name: "gltf",
        run: gltf,
    },
    Target {
        name: "texture",
        run: texture,
    },
    Target {
        name: "pack",
        run: pack,
    },
    Target {
        name: "hdr",
        run: hdr,
    },
];

/// The repository's folder.
pub fn repo_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Folder scene text is resolved against: `fuzz/assets/`, small stand-ins for the meshes and
/// textures of `scenes/` that the seed scenes name, so that an input's work stays small.
pub fn assets_dir() -> PathBuf {
    repo_dir().join("fuzz/assets")
}

/// Folder OBJ text is resolved against: the Cornell box's, so `mtllib CornellBox-Original.mtl`
/// is found.
fn obj_dir() -> PathBuf {
    assets_dir().join("cornell_box")
}

/// A TOML scene file: parsed, built, rendered small.
pub fn scene_toml(data: &[u8]) {
    scene(data, SceneFormat::Toml);
}

/// A JSON scene file: parsed, built, rendered small.
pub fn scene_json(data: &[u8]) {
    scene(data, SceneFormat::Json);
}

/// A TOML scene file with an override (`penumbra render --set KEY.PATH=VALUE`) on its first
/// line: parsed, the override applied, built, rendered small.
pub fn scene_override(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let (first, rest) = text.split_once('\n').unwrap_or((text, ""));
    // A malformed override is the command line's error, echoed as given (clap does too).
    if let Ok(o) = Override::parse(first) {
        scene_with(rest, SceneFormat::Toml, &[o]);
    }
}

fn scene(data: &[u8], format: SceneFormat) {
    // Scene files are UTF-8; `SceneFile::load` refuses other bytes before parsing.
    if let Ok(text) = std::str::from_utf8(data) {
        scene_with(text, format, &[]);
    }
}

/// The folder a fuzzed pack's relative paths resolve against: its files are packed under it,
/// and nothing there is on disk.
pub const PACK_DIR: &str = "/penumbra-fuzz-pack";

/// A scene pack as `penumbra.load_pack` receives it (from a pickle, from another machine),
/// parsed, built from its files alone and rendered small. The input: the overrides (one per
/// line), a NUL byte, the TOML scene text, a NUL byte, then for each packed file its path
/// (relative to [`PACK_DIR`]), a NUL byte, its length (4 bytes, little-endian; cut to what is
/// left) and its bytes.
pub fn pack(data: &[u8]) {
    let file = decode_pack(data).load();
    if let Ok(f) = &file {
        assert!(f.files().is_packed(), "a pack reads files from disk");
    }
    build_and_render(file);
}

/// The pack an input of [`pack`] describes.
pub fn decode_pack(data: &[u8]) -> ScenePack {
    let (overrides, rest) = until_nul(data);
    let (scene, mut rest) = until_nul(rest);
    let mut files = BTreeMap::new();
    while !rest.is_empty() {
        let (path, after) = until_nul(rest);
        let (len, after) = after.split_at(after.len().min(4));
        let mut le = [0u8; 4];
        le[..len.len()].copy_from_slice(len);
        let (bytes, after) = after.split_at(after.len().min(u32::from_le_bytes(le) as usize));
        let path = Path::new(PACK_DIR).join(String::from_utf8_lossy(path).as_ref());
        files.insert(path, bytes.to_vec());
        rest = after;
    }
    ScenePack {
        name: PathBuf::from("fuzz.toml"),
        text: String::from_utf8_lossy(scene).into_owned(),
        format: SceneFormat::Toml,
        base_dir: PathBuf::from(PACK_DIR),
        overrides: String::from_utf8_lossy(overrides)
            .lines()
            .map(str::to_owned)
            .collect(),
        allowed: Vec::new(),
        files,
    }
}

/// The bytes before the first NUL, and those after it (none when there is no NUL).
fn until_nul(data: &[u8]) -> (&[u8], &[u8]) {
    match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[]),
    }
}

fn scene_with(text: &str, format: SceneFormat, overrides: &[Override]) {
    build_and_render(SceneFile::from_str_with(
        text,
        format,
        "fuzz",
        assets_dir(),
        overrides,
    ));
}

/// A parsed scene file built and rendered small; an error is checked to be one clean line.
fn build_and_render(file: Result<SceneFile, SceneError>) {
    let file = match file {
        Ok(file) => file,
        Err(e) => return check_message(&e),
    };
    let scene = match file.build(1) {
        Ok(scene) => scene,
        Err(e) => return check_message(&e),
    };
    check_world(&scene.world);
    let settings = RenderSettings {
        width: 4,
        height: 4,
        spp: 1,
        light_samples: Some(1),
        ..scene.settings.clone()
    };
    let options = RenderOptions {
        threads: 1,
        ..RenderOptions::default()
    };
    // What the build accepts renders: its checks are the renderer's.
    let (film, _) = match render(&scene.world, &settings, &options) {
        Ok(rendered) => rendered,
        Err(e) => panic!("the scene builds but does not render: {e}"),
    };
    for (i, p) in film.pixels.iter().enumerate() {
        assert!(p.is_finite(), "pixel {i} is {p}");
    }
}

/// An error's promise: one line a terminal can show as it is, whatever bytes the file holds
/// (no newline, ESC, BEL or other control character).
fn check_message(e: &SceneError) {
    let message = e.to_string();
    assert!(
        !message.chars().any(char::is_control),
        "a control character in the message {message:?}"
    );
}

/// A built world's promises: finite vertices, normals, uvs and bounds, a valid BVH, finite
/// lights.
pub fn check_world(world: &World) {
    let g = world.geometry();
    assert!(
        g.positions.iter().all(|p| p.is_finite()),
        "a vertex is not finite"
    );
    assert!(
        g.normals.iter().all(|n| n.is_finite()),
        "a normal is not finite"
    );
    assert!(g.uvs.iter().all(|uv| uv.is_finite()), "a uv is not finite");
    check_bounds(&world.bounds(), g.triangles.is_empty());
    if let Err(e) = world.accel().validate(g) {
        panic!("invalid BVH: {e}");
    }
    for light in world.lights() {
        let finite = match light {
            Light::Area(a) => [a.center, a.u, a.v, a.radiance]
                .iter()
                .all(|v| v.is_finite()),
            Light::Point(p) => p.position.is_finite() && p.intensity.is_finite(),
            Light::Environment(e) => e.intensity.is_finite() && e.rotation.is_finite(),
            Light::Directional(d) => d.direction.is_finite() && d.irradiance.is_finite(),
            Light::Spot(s) => [s.position, s.direction, s.intensity]
                .iter()
                .all(|v| v.is_finite()),
        };
        assert!(finite, "{light:?}");
    }
}

fn check_bounds(bounds: &Aabb, empty: bool) {
    if !empty {
        assert!(
            bounds.min.is_finite() && bounds.max.is_finite() && bounds.min.cmple(bounds.max).all(),
            "bounds {bounds:?}"
        );
    }
}

/// An OBJ file (its `mtllib` names resolved in the Cornell box's folder).
pub fn obj(data: &[u8]) {
    let Ok(info) = inspect_obj_bytes(data, &obj_dir()) else {
        return;
    };
    // A mesh without faces is an error, so the bounds hold at least one vertex.
    assert!(info.triangles > 0, "an OBJ without faces was accepted");
    check_bounds(&info.bounds, false);
}

/// A PLY file, ASCII or binary; an ASCII one's rows are lines (see `formats`).
pub fn ply(data: &[u8]) {
    let Ok(info) = inspect_ply_bytes(data) else {
        return;
    };
    // A mesh without triangles is an error, so the bounds hold at least one vertex.
    assert!(info.triangles > 0, "a PLY without triangles was accepted");
    assert!(info.vertices > 0);
    check_bounds(&info.bounds, false);
    formats::check_ply_rows(data, &info);
}

/// A glTF file, GLB or JSON (by its first bytes), with at most 64 MiB of geometry; its
/// external files are looked for in a folder that does not exist. An error names its JSON
/// path (see `formats`).
pub fn gltf(data: &[u8]) {
    const MAX_BYTES: u64 = 64 << 20;
    let dir = repo_dir().join("fuzz/no-such-folder");
    let info = match inspect_gltf_bytes(data, &dir, Some(MAX_BYTES)) {
        Ok(info) => info,
        Err(message) => return formats::check_gltf_message(&message),
    };
    // A scene without triangles is an error, so the bounds hold at least one vertex.
    assert!(info.triangles > 0, "a glTF without triangles was accepted");
    assert!(info.unique_triangles <= info.triangles);
    check_bounds(&info.bounds, false);
}

/// An MTL file.
pub fn mtl(data: &[u8]) {
    let _ = inspect_mtl(data, &obj_dir().join("fuzz.mtl"));
}

/// A PNG or JPEG texture, decoded with a bound on its memory (as a scene's build does) in
/// both color spaces.
pub fn texture(data: &[u8]) {
    // 64 MiB: a few million texels, decoded in well under a second.
    const MAX_BYTES: u64 = 64 << 20;
    for srgb in [true, false] {
        let Ok(image) = decode_texture_image(data, srgb, Some(MAX_BYTES)) else {
            return;
        };
        assert!(image.width > 0 && image.height > 0);
        assert_eq!(
            image.texels.len(),
            image.width as usize * image.height as usize
        );
        assert!(image.texels.iter().all(|t| t.is_finite()));
    }
}
