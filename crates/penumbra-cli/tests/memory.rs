//! Scenes too large for the memory the process may take (issue 10, class 7), run under an
//! address-space limit (`ulimit -v`) so that the outcome does not depend on the machine: 3000
//! spheres (27 million triangles), and small PNG files that each declare 8192 × 8192 texels.
//! Each is refused with exit 2 naming the object or texture that does not fit, never an abort
//! from a failed allocation.
#![cfg(target_os = "linux")]

#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use std::path::Path;
use std::process::{Command, Stdio};

use support::TempDir;

const HEAD: &str = r#"[film]
width = 8
height = 8

[camera]
position = [0, 1, 50]
look_at = [0, 0, 0]
fov = 45

[[lights]]
type = "point"
position = [0, 50, 50]
"#;

/// Runs `penumbra render SCENE -o OUT` with at most `kib` KiB of address space; its exit
/// code and stderr.
fn render_limited(scene: &Path, out: &Path, kib: u64) -> (Option<i32>, String) {
    render_limited_with(scene, out, kib, &[])
}

/// [`render_limited`] with more arguments.
fn render_limited_with(scene: &Path, out: &Path, kib: u64, args: &[&str]) -> (Option<i32>, String) {
    let run = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {kib} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_penumbra"))
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .arg("--quiet")
        .args(args)
        .env_remove("RUST_BACKTRACE")
        .stdin(Stdio::null())
        .output()
        .expect("run sh");
    (
        run.status.code(),
        String::from_utf8_lossy(&run.stderr).into_owned(),
    )
}

fn assert_refused(what: &str, got: (Option<i32>, String), key: &str, out: &Path) {
    let (code, stderr) = got;
    assert_eq!(code, Some(2), "{what}: exit code; stderr: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "{what}: {stderr}");
    assert!(stderr.starts_with("error: "), "{what}: {stderr}");
    assert!(
        stderr.contains(key),
        "{what}: does not name {key}: {stderr}"
    );
    assert!(stderr.contains("memory"), "{what}: {stderr}");
    assert!(!out.exists(), "{what}: an image was written");
}

#[test]
fn three_thousand_spheres_beyond_the_memory_limit_are_refused_at_an_object() {
    let sb = TempDir::new("memory-spheres");
    let mut text = HEAD.to_owned();
    for i in 0..3000 {
        text += &format!(
            "\n[[objects]]\ntype = \"sphere\"\ncenter = [{}, {}, 0]\nradius = 0.4\n",
            i % 60,
            i / 60
        );
    }
    let scene = sb.write("spheres.toml", text);
    let out = sb.join("out.png");
    let got = render_limited(&scene, &out, 2_000_000);
    assert_refused("3000 spheres", got, ": objects[", &out);
}

#[test]
fn small_pngs_declaring_huge_images_beyond_the_memory_limit_are_refused_at_a_texture() {
    let sb = TempDir::new("memory-textures");
    // 8192 × 8192 of one grey compresses to a few hundred kilobytes.
    let png = sb.join("t0.png");
    let file = std::fs::File::create(&png).unwrap();
    let encoder = image::codecs::png::PngEncoder::new_with_quality(
        std::io::BufWriter::new(file),
        image::codecs::png::CompressionType::Default,
        image::codecs::png::FilterType::NoFilter,
    );
    image::ImageEncoder::write_image(
        encoder,
        &vec![128u8; 8192 * 8192 * 3],
        8192,
        8192,
        image::ExtendedColorType::Rgb8,
    )
    .unwrap();
    let size = std::fs::metadata(&png).unwrap().len();
    assert!(size < 4 << 20, "{size} bytes");
    let mut text = HEAD.to_owned();
    for i in 0..4 {
        if i > 0 {
            std::fs::copy(&png, sb.join(format!("t{i}.png"))).unwrap();
        }
        text += &format!(
            "\n[materials.m{i}]\ntexture = \"t{i}\"\n\n[textures.t{i}]\ntype = \"image\"\n\
             file = \"t{i}.png\"\n\n[[objects]]\ntype = \"cube\"\nmaterial = \"m{i}\"\n\
             center = [{i}, 0, 0]\nsize = 0.5\n"
        );
    }
    let scene = sb.write("textures.toml", text);
    let out = sb.join("out.png");
    let got = render_limited(&scene, &out, 3_000_000);
    assert_refused("four 8192² PNGs", got, ": textures.t", &out);
}

/// Issue 30, class 1: a 7000 × 7000 film fits in 1 GiB, but the render kept a second copy of
/// every pixel (its tiles' values) until the end, and aborted. Under 1 GiB, films from 6000²
/// (which fits) to 9000² (which never does) either render and write their image or end with
/// one line about memory, exit 1, and no file; never an abort.
#[test]
fn large_films_under_one_gib_render_or_are_refused_in_one_line() {
    let sb = TempDir::new("memory-film");
    let text = format!("{HEAD}\n[[objects]]\ntype = \"cube\"\ncenter = [0, 0, 0]\nsize = 1\n");
    let scene = sb.write("film.toml", text);
    for side in ["6000", "7000", "8000", "9000"] {
        let out = sb.join(format!("out{side}.png"));
        let args = ["--width", side, "--height", side, "--spp", "1"];
        let (code, stderr) = render_limited_with(&scene, &out, 1 << 20, &args);
        match code {
            Some(0) => assert!(out.exists(), "{side}: no image"),
            Some(1) => {
                assert_eq!(stderr.lines().count(), 1, "{side}: {stderr}");
                assert!(stderr.contains("memory"), "{side}: {stderr}");
                assert!(
                    stderr.contains(&format!("{side}x{side}")),
                    "{side}: {stderr}"
                );
                assert!(!out.exists(), "{side}: an image was written");
            }
            other => panic!("{side}: exit {other:?}: {stderr}"),
        }
        let _ = std::fs::remove_file(&out);
    }
}

/// A `.npy` file whose header declares `rows` float32 4×4 matrices, made as large as they need
/// but sparse (no data is written).
fn sparse_npy(path: &Path, rows: u64) {
    let bytes = support::npy("<f4", &format!("({rows}, 4, 4)"), &[]);
    let header = bytes.len() as u64;
    std::fs::write(path, bytes).unwrap();
    let file = std::fs::OpenOptions::new().write(true).open(path).unwrap();
    file.set_len(header + rows * 64).unwrap();
}

#[test]
fn transforms_beyond_the_memory_limit_or_the_instance_limit_are_refused_before_reading() {
    let sb = TempDir::new("memory-instances");
    sb.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let text = format!(
        "{HEAD}\n[[objects]]\ntype = \"instances\"\nfile = \"tri.obj\"\ntransforms = \"t.npy\"\n"
    );
    let scene = sb.write("instances.toml", text);
    let out = sb.join("out.png");
    // 10^7 instances: about 5 GB to place, beyond a 2 GB address space.
    sparse_npy(&sb.join("t.npy"), 10_000_000);
    let got = render_limited(&scene, &out, 2_000_000);
    assert_refused("10^7 instances", got, ": objects[0].transforms", &out);
    // 10^8: beyond the most a scene places, whatever the memory.
    sparse_npy(&sb.join("t.npy"), 100_000_000);
    let (code, stderr) = render_limited(&scene, &out, 2_000_000);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(
        stderr.contains("objects[0].transforms") && stderr.contains("at most 16777216"),
        "{stderr}"
    );
    assert!(!out.exists(), "an image was written");
}
