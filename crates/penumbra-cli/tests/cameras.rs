//! Several cameras in one run (`--camera all`, comma lists, `*`/`?` patterns) from one loaded
//! scene, and output patterns: `{camera}`, `{scene}`, `{spp}`, `{seed}` in `-o`.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use harness::{error_line, image, ok, run_in};
use support::{TempDir, BASE_TOML};

/// The base scene seen by three named cameras: front, side_left and top.
fn three_cameras() -> String {
    BASE_TOML.replace(
        "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\nfov = 45\n",
        "[cameras.front]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\nfov = 45\n\
         [cameras.side_left]\nposition = [-5, 1, 0]\nlook_at = [0, 0, 0]\nfov = 45\n\
         [cameras.top]\nposition = [0, 6, 0.01]\nlook_at = [0, 0, 0]\nfov = 45\n",
    )
}

fn files(dir: &TempDir, sub: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir.join(sub))
        .map(|d| {
            d.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

#[test]
fn all_cameras_render_into_the_expanded_pattern() {
    let dir = TempDir::new("cams-all");
    dir.write("room.toml", three_cameras());
    let r = ok(run_in(
        dir.path(),
        [
            "render",
            "room.toml",
            "--camera",
            "all",
            "-o",
            "out/{scene}_{camera}_{spp}spp_s{seed}.png",
            "--seed",
            "3",
            "--json",
        ],
    ));
    assert_eq!(
        files(&dir, "out"),
        [
            "room_front_4spp_s3.png",
            "room_side_left_4spp_s3.png",
            "room_top_4spp_s3.png"
        ]
    );
    // One JSON object per render, and with --json no summary line on stderr.
    assert_eq!(r.stderr.lines().count(), 0, "{}", r.stderr);
    let cameras: Vec<String> = r
        .out()
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()["camera"].to_string())
        .collect();
    assert_eq!(cameras, ["\"front\"", "\"side_left\"", "\"top\""]);
    // Each image is what rendering that camera alone gives.
    for cam in ["front", "side_left", "top"] {
        let single = format!("{cam}.png");
        ok(run_in(
            dir.path(),
            [
                "render",
                "room.toml",
                "--camera",
                cam,
                "-o",
                &single,
                "--seed",
                "3",
                "-q",
            ],
        ));
        let many = dir.join(format!("out/room_{cam}_4spp_s3.png"));
        assert_eq!(image(&many), image(&dir.join(&single)), "{cam}");
    }
    assert_ne!(
        image(&dir.join("front.png")),
        image(&dir.join("top.png")),
        "the cameras see different images"
    );
}

#[test]
fn lists_and_patterns_choose_cameras_in_order() {
    let dir = TempDir::new("cams-list");
    dir.write("room.toml", three_cameras());
    let r = ok(run_in(
        dir.path(),
        [
            "render",
            "room.toml",
            "--camera",
            "top, s*,top",
            "-o",
            "{camera}.png",
            "--quick",
        ],
    ));
    let order: Vec<&str> = r
        .stderr
        .lines()
        .map(|l| l.rsplit("-> ").next().unwrap())
        .collect();
    assert_eq!(order, ["top.png", "side_left.png"]);
    ok(run_in(
        dir.path(),
        [
            "render",
            "room.toml",
            "--camera",
            "?ro*",
            "-o",
            "p/{camera}.png",
            "-q",
        ],
    ));
    assert_eq!(files(&dir, "p"), ["front.png"]);
}

#[test]
fn the_default_camera_fills_the_pattern_too() {
    let dir = TempDir::new("cams-default-pattern");
    dir.write("room.toml", three_cameras());
    ok(run_in(
        dir.path(),
        ["render", "room.toml", "-o", "{camera}.png", "-q"],
    ));
    assert!(dir.join("front.png").exists());
    // film.output is a pattern as well.
    let with_output = three_cameras().replace(
        "height = 12\n",
        "height = 12\noutput = \"o/{camera}.png\"\n",
    );
    dir.write("out.toml", with_output);
    ok(run_in(
        dir.path(),
        ["render", "out.toml", "--camera", "all", "-q"],
    ));
    assert_eq!(files(&dir, "o"), ["front.png", "side_left.png", "top.png"]);
}

#[test]
fn without_o_several_cameras_go_beside_the_scene() {
    let dir = TempDir::new("cams-default");
    dir.write("room.toml", three_cameras());
    ok(run_in(
        dir.path(),
        ["render", "room.toml", "--camera", "front,top", "-q"],
    ));
    assert!(dir.join("room_front.png").exists());
    assert!(dir.join("room_top.png").exists());
}

#[test]
fn camera_and_pattern_mistakes_are_input_errors() {
    let dir = TempDir::new("cams-errors");
    dir.write("room.toml", three_cameras());
    let cases: [(&[&str], &str); 6] = [
        (
            &["--camera", "all", "-o", "one.png"],
            "3 cameras need {camera}",
        ),
        (
            &["--camera", "x*", "-o", "{camera}.png"],
            "no camera matches `x*`",
        ),
        (
            &["--camera", "front,nope", "-o", "{camera}.png"],
            "no camera named \"nope\"",
        ),
        (&["-o", "{frames}.png"], "unknown field `{frames}`"),
        // {frame} is a path camera's frame (tests/sequences.rs); a still camera has none.
        (&["-o", "{frame}.png"], "still camera"),
        (
            &["--camera", "front,", "-o", "{camera}.png"],
            "an empty name",
        ),
    ];
    for (extra, words) in cases {
        let mut args = vec!["render", "room.toml"];
        args.extend(extra);
        let r = run_in(dir.path(), &args);
        let line = error_line(&r, 2);
        assert!(line.contains(words), "{args:?}: {line}");
        // Checked before any render: nothing written.
        let pngs: Vec<String> = files(&dir, ".")
            .into_iter()
            .filter(|n| n.ends_with(".png"))
            .collect();
        assert!(pngs.is_empty(), "{args:?} wrote {pngs:?}");
    }
}

#[test]
fn camera_names_with_path_syntax_stay_inside_the_output_folder() {
    // Each name as a scene file may spell it (a TOML basic string), and the file it gives in
    // `o/{camera}/image.png`: one folder of its own under `o`, never `o/..` or deeper.
    let cases = [
        ("..", "_."),
        (".", "_"),
        ("../../up", "_._.._up"),
        ("a/b", "a_b"),
        ("back\\\\slash", "back_slash"),
        ("-dash", "_dash"),
        ("tab\\there", "tab_here"),
    ];
    for (spelled, folder) in cases {
        let dir = TempDir::new("cams-path-syntax");
        let scene = BASE_TOML.replace("[camera]\n", &format!("[cameras.\"{spelled}\"]\n"));
        dir.write("in/room.toml", scene);
        ok(run_in(
            &dir.join("in"),
            ["render", "room.toml", "-o", "o/{camera}/image.png", "-q"],
        ));
        assert_eq!(files(&dir, "in/o"), [folder], "{spelled}");
        assert!(dir.join("in/o").join(folder).join("image.png").is_file());
        // Nothing beside the scene's folder, nor beside the output folder.
        assert_eq!(files(&dir, "."), ["in"], "{spelled}");
        assert_eq!(files(&dir, "in"), ["o", "room.toml"], "{spelled}");
    }
}
