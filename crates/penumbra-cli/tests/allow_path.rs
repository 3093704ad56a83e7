//! `--allow-path DIR`: a scene reads only files in its folder and below (a model in its own),
//! unless a folder is allowed; a refusal is an input error (exit 2) naming the file, the key,
//! the reference and the rule.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use harness::{error_line, ok, run_in, run_with};
use support::{line_of, with_mesh, TempDir};

const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

#[test]
fn a_file_outside_the_scene_folder_is_refused_unless_allowed() {
    let dir = TempDir::new("allow-path");
    dir.write("assets/tri.obj", TRIANGLE);
    let text = with_mesh("../assets/tri.obj");
    dir.write("scenes/s.toml", &text);
    let line = line_of(&text, "file = ");
    for command in ["render", "check"] {
        let r = run_in(dir.path(), [command, "scenes/s.toml"]);
        let e = error_line(&r, 2);
        assert_eq!(
            e,
            format!(
                "error: scenes/s.toml:{line}:1: objects[2].file: \"../assets/tri.obj\" is \
                 outside the scene's folder scenes/ (a file reads only files in its own folder \
                 and below; --allow-path DIR (allow_paths= in Python) widens that)"
            ),
            "{command}"
        );
        let allowed = [command, "scenes/s.toml", "--allow-path", "assets"];
        ok(run_in(dir.path(), allowed));
    }
    assert!(dir.join("scenes/s.png").exists());
    // Another folder allowed is not this one; a folder that is not one is refused.
    dir.write("other/x.txt", "");
    let r = run_in(
        dir.path(),
        ["check", "scenes/s.toml", "--allow-path", "other"],
    );
    assert!(error_line(&r, 2).contains("is outside the scene's folder"));
    let r = run_in(
        dir.path(),
        ["check", "scenes/s.toml", "--allow-path", "nope"],
    );
    assert_eq!(error_line(&r, 2), "error: --allow-path nope: not a folder");
}

#[test]
fn a_model_and_a_scene_on_stdin_have_their_own_roots() {
    let dir = TempDir::new("allow-path-model");
    dir.write("shared/lib.mtl", "newmtl m\nKd 1 0 0\n");
    dir.write(
        "model/m.obj",
        format!("mtllib ../shared/lib.mtl\n{TRIANGLE}"),
    );
    for command in ["render", "check"] {
        let r = run_in(dir.path(), [command, "model/m.obj"]);
        let e = error_line(&r, 2);
        assert!(
            e.contains("`mtllib` \"../shared/lib.mtl\" is outside the model's folder model/"),
            "{command}: {e}"
        );
        let allowed = [command, "model/m.obj", "--allow-path", "shared"];
        ok(run_in(dir.path(), allowed));
    }
    // Standard input's folder is the current one.
    let text = with_mesh("model/m.obj");
    let r = run_with(dir.path(), ["check", "-"], Some(text.as_bytes()));
    assert!(error_line(&r, 2).contains("`mtllib`"));
    let r = run_with(
        dir.join("model").as_path(),
        ["check", "-", "--allow-path", "../shared"],
        Some(with_mesh("m.obj").as_bytes()),
    );
    ok(r);
}
