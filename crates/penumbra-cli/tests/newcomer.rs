//! What a newcomer meets first: flags spelled as other renderers spell them, and messages in
//! the words typed on the command line (flag values and file extensions, never Rust names).

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use harness::{error_line, image, ok, run_in};
use support::{TempDir, BASE_TOML};

fn scene_dir(name: &str) -> TempDir {
    let dir = TempDir::new(name);
    dir.write("s.toml", BASE_TOML);
    dir
}

#[test]
fn samples_is_another_name_for_spp() {
    let dir = scene_dir("samples-alias");
    let r = ok(run_in(
        dir.path(),
        ["render", "s.toml", "-o", "a.png", "--samples", "16"],
    ));
    assert!(r.stderr.contains(", 16 spp rgss,"), "{}", r.stderr);
    ok(run_in(
        dir.path(),
        ["render", "s.toml", "-o", "b.png", "--spp", "16", "-q"],
    ));
    assert_eq!(image(&dir.join("a.png")), image(&dir.join("b.png")));
    // Still a perfect square, and the message names the flag as documented.
    let r = run_in(
        dir.path(),
        ["render", "s.toml", "-o", "c.png", "--samples", "3"],
    );
    assert!(error_line(&r, 2).contains("perfect square"), "{r:?}");
    assert!(!dir.join("c.png").exists());
}

#[test]
fn a_format_that_disagrees_with_the_name_says_so_in_flag_values() {
    let dir = scene_dir("format-words");
    for (format, out, want) in [
        (
            "jpg",
            "out.png",
            "error: --format jpg disagrees with the extension of out.png (png): drop --format, or name the file .jpg",
        ),
        (
            "jpeg",
            "out.exr",
            "error: --format jpg disagrees with the extension of out.exr (exr): drop --format, or name the file .jpg",
        ),
        (
            "pfm",
            "out.JPEG",
            "error: --format pfm disagrees with the extension of out.JPEG (jpg): drop --format, or name the file .pfm",
        ),
    ] {
        let r = run_in(
            dir.path(),
            ["render", "s.toml", "--format", format, "-o", out],
        );
        assert_eq!(error_line(&r, 2), want);
        assert!(!dir.join(out).exists());
    }
}

#[test]
fn a_file_of_another_kind_is_told_what_each_subcommand_reads() {
    let dir = scene_dir("file-kinds");
    dir.write("model.fbx", "Kaydara FBX Binary");
    dir.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    dir.write(
        "tri.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
         end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    );
    let check = "`penumbra check` reads a .toml or .json scene file, or a .obj, .ply, .gltf or \
                 .glb model";
    let render = "`penumbra render` reads a .toml or .json scene file, or a .obj, .ply, .gltf or \
                  .glb model";
    for (args, want) in [
        (["check", "model.fbx"], check),
        (["render", "model.fbx"], render),
    ] {
        let line = error_line(&run_in(dir.path(), args), 2);
        assert!(line.starts_with(&format!("error: {}: ", args[1])), "{line}");
        assert!(line.contains(want), "{args:?}: {line}");
    }
    // Both subcommands read the meshes: render as a scene of their own.
    for mesh in ["tri.obj", "tri.ply"] {
        ok(run_in(
            dir.path(),
            [
                "render",
                mesh,
                "--set",
                "film.width=8",
                "--set",
                "film.height=6",
                "-q",
            ],
        ));
        ok(run_in(dir.path(), ["check", mesh]));
    }
    assert_eq!(image(&dir.join("tri.png")).dimensions(), (8, 6));
}

#[test]
fn overrides_on_a_bare_mesh_are_refused_not_ignored() {
    let dir = scene_dir("mesh-set");
    dir.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let r = run_in(dir.path(), ["check", "tri.obj", "--set", "film.width=3"]);
    let line = error_line(&r, 2);
    assert!(line.starts_with("error: --set film.width=3: "), "{line}");
    assert!(r.stdout.is_empty(), "{}", r.out());
}

#[test]
fn quick_with_a_sample_count_keeps_the_scenes_sampler() {
    let dir = scene_dir("quick-spp");
    let r = ok(run_in(
        dir.path(),
        ["render", "s.toml", "-o", "q.png", "--quick", "--spp", "16"],
    ));
    // A quarter of 16x12, 16 samples with the file's sampler (rgss by default), 1 light sample.
    assert!(
        r.stderr.contains("4x3, 16 spp rgss, 1 light sample, "),
        "{}",
        r.stderr
    );
    // Without a count the preview is center sampling, 1 sample.
    let r = ok(run_in(
        dir.path(),
        ["render", "s.toml", "-o", "c.png", "--quick"],
    ));
    assert!(r.stderr.contains("4x3, 1 spp center, "), "{}", r.stderr);
    // An explicit center sampler with a count above 1 is still refused, naming --spp.
    let r = run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "-o",
            "x.png",
            "--quick",
            "--sampler",
            "center",
            "--spp",
            "4",
        ],
    );
    assert!(error_line(&r, 2).starts_with("error: --spp: "), "{r:?}");
}
