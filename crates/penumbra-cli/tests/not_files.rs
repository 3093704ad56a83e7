//! Paths that are not regular files (issue 10, class 4), in every place a scene names a file:
//! the scene itself, a mesh, the MTL library a mesh names and a texture, each as a folder, a
//! named pipe and a device (`/dev/zero`). Each is refused at once with exit 2 and one line,
//! never read (a pipe would block, `/dev/zero` never ends).
#![cfg(unix)]

#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use support::{with_mesh, with_texture, TempDir};

/// Runs `penumbra render SCENE -o OUT` for at most 10 s; its exit code (`None`: it had to be
/// killed) and stderr. `/dev` is allowed: a device is outside every scene's folder, and here
/// the reference must reach the check of what it is.
fn render_bounded(scene: &Path, out: &Path) -> (Option<i32>, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .env_remove("RUST_BACKTRACE")
        .arg("render")
        .arg(scene)
        .args(["--allow-path", "/dev"])
        .arg("-o")
        .arg(out)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(10) {
            let _ = child.kill();
            let _ = child.wait();
            return (None, String::new());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let out = child.wait_with_output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The three kinds of non-files at `dir/name`: a folder, a named pipe (when `mkfifo` works)
/// and `/dev/zero` (by a symbolic link, so that the name keeps its extension).
fn non_files(dir: &TempDir, name: &str) -> Vec<(PathBuf, &'static str)> {
    let mut all = Vec::new();
    let folder = dir.join(format!("folder/{name}"));
    std::fs::create_dir_all(&folder).unwrap();
    all.push((folder, "folder"));
    let fifo = dir.join(format!("fifo/{name}"));
    std::fs::create_dir_all(fifo.parent().unwrap()).unwrap();
    if Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        all.push((fifo, "not a regular file"));
    }
    let device = dir.join(format!("device/{name}"));
    std::fs::create_dir_all(device.parent().unwrap()).unwrap();
    std::os::unix::fs::symlink("/dev/zero", &device).unwrap();
    all.push((device, "not a regular file"));
    all
}

#[test]
fn scenes_meshes_mtl_libraries_and_textures_must_be_regular_files() {
    let sb = TempDir::new("not-files-matrix");
    let out = sb.join("out.png");
    let mut cases: Vec<(String, PathBuf, &str)> = Vec::new();
    for (path, words) in non_files(&sb, "s.toml") {
        cases.push((format!("scene {}", path.display()), path, words));
    }
    for (path, words) in non_files(&sb, "m.obj") {
        let scene = sb.write(
            format!("mesh-{}.toml", cases.len()),
            with_mesh(&path.display().to_string()),
        );
        cases.push((format!("mesh {}", path.display()), scene, words));
    }
    for (path, words) in non_files(&sb, "m.mtl") {
        let obj = sb.write(
            format!("mtl-{}.obj", cases.len()),
            format!(
                "mtllib {}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
                path.display()
            ),
        );
        let scene = sb.write(
            format!("mtl-{}.toml", cases.len()),
            with_mesh(&obj.display().to_string()),
        );
        cases.push((format!("MTL {}", path.display()), scene, words));
    }
    for (path, words) in non_files(&sb, "t.png") {
        let scene = sb.write(
            format!("texture-{}.toml", cases.len()),
            with_texture(&path.display().to_string()),
        );
        cases.push((format!("texture {}", path.display()), scene, words));
    }
    for (what, scene, words) in &cases {
        let start = Instant::now();
        let (code, stderr) = render_bounded(scene, &out);
        assert_eq!(code, Some(2), "{what}: exit code; stderr: {stderr}");
        assert!(
            start.elapsed() < Duration::from_secs(5),
            "{what}: took {:?}",
            start.elapsed()
        );
        assert!(stderr.contains(words), "{what}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{what}: {stderr}");
        assert!(!out.exists(), "{what}: an image was written");
    }
}
