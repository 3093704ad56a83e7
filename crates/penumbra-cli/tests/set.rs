//! `--set KEY.PATH=VALUE` and its alias `-D`: any scene key overridden from the command line,
//! checked like the file, with errors that name `--set` and the key. (The rules of paths and
//! values are tested on the library, in `crates/penumbra/tests/overrides.rs`.)

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use harness::{error_line, image, ok, run_in};
use support::{TempDir, BASE_TOML};

#[test]
fn set_changes_the_render_like_the_file_would() {
    let dir = TempDir::new("set-render");
    dir.write("s.toml", BASE_TOML);
    let edited = BASE_TOML
        .replace("width = 16", "width = 10")
        .replace("diffuse = [0.8, 0.1, 0.1]", "diffuse = [0.1, 0.1, 0.8]");
    dir.write("edited.toml", edited);
    ok(run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "-o",
            "set.png",
            "--set",
            "film.width=10",
            "-D",
            "materials.red.diffuse=[0.1, 0.1, 0.8]",
            "-q",
        ],
    ));
    ok(run_in(
        dir.path(),
        ["render", "edited.toml", "-o", "file.png", "-q"],
    ));
    let (a, b) = (image(&dir.join("set.png")), image(&dir.join("file.png")));
    assert_eq!(a.dimensions(), (10, 12));
    assert_eq!(
        a, b,
        "--set and the same edit in the file must give the same image"
    );
}

#[test]
fn flags_still_win_over_set() {
    let dir = TempDir::new("set-flags");
    dir.write("s.toml", BASE_TOML);
    let r = ok(run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "-o",
            "o.png",
            "-D",
            "film.width=10",
            "--width",
            "8",
            "--json",
            "-q",
        ],
    ));
    assert!(r.out().contains("\"width\":8"), "{}", r.out());
}

#[test]
fn bad_overrides_name_set_and_the_key() {
    let dir = TempDir::new("set-errors");
    dir.write("s.toml", BASE_TOML);
    let cases: [(&str, &[&str]); 5] = [
        ("film.width=wide", &["film.width", "expected an integer"]),
        ("film.widht=3", &["film.widht", "unknown field `widht`"]),
        (
            "objects[1].material=blue",
            &["objects[1].material", "unknown material \"blue\""],
        ),
        ("objects.7.material=red", &["objects", "2 entries"]),
        ("render.samples=3", &["render.samples", "perfect square"]),
    ];
    for (set, words) in cases {
        let render = ["render", "s.toml", "-o", "o.png", "--set", set];
        let check = ["check", "s.toml", "--set", set, "--json"];
        for r in [run_in(dir.path(), render), run_in(dir.path(), check)] {
            assert!(r.stdout.is_empty(), "{}", r.out());
            let line = error_line(&r, 2);
            assert!(line.starts_with("error: s.toml: "), "{line}");
            assert!(line.contains(&format!("(--set {set})")), "{line}");
            for w in words {
                assert!(line.contains(w), "{line} lacks {w}");
            }
            assert!(!dir.join("o.png").exists());
        }
    }
}

#[test]
fn a_malformed_override_is_a_usage_error() {
    let dir = TempDir::new("set-usage");
    dir.write("s.toml", BASE_TOML);
    let r = run_in(dir.path(), ["render", "s.toml", "--set", "film.width"]);
    let line = error_line(&r, 2);
    assert!(line.contains("--set"), "{line}");
    assert!(line.contains("KEY.PATH=VALUE"), "{line}");
}
