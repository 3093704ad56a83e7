//! `penumbra completions SHELL`: a completion script that knows the subcommands and flags.

mod harness;

use std::process::{Command, Stdio};

use harness::{ok, run_in};

fn script(shell: &str) -> String {
    ok(run_in(&std::env::temp_dir(), ["completions", shell])).out()
}

#[test]
fn each_shell_completes_the_subcommands_and_flags() {
    for shell in ["bash", "zsh", "fish"] {
        let s = script(shell);
        for word in ["render", "check", "completions"] {
            assert!(s.contains(word), "{shell}: no `{word}`");
        }
        // fish spells long flags `-l camera`.
        let (camera, aov) = if shell == "fish" {
            ("-l camera", "-l aov")
        } else {
            ("--camera", "--aov")
        };
        assert!(s.contains(camera), "{shell}: no {camera}");
        assert!(s.contains(aov), "{shell}: no {aov}");
    }
}

#[test]
fn the_bash_script_is_valid_bash() {
    let s = script("bash");
    let Ok(mut child) = Command::new("bash").arg("-n").stdin(Stdio::piped()).spawn() else {
        eprintln!("no bash here: syntax not checked");
        return;
    };
    use std::io::Write;
    child.stdin.take().unwrap().write_all(s.as_bytes()).unwrap();
    assert!(
        child.wait().unwrap().success(),
        "bash -n rejects the script"
    );
}

#[test]
fn an_unknown_shell_is_a_usage_error() {
    let r = run_in(&std::env::temp_dir(), ["completions", "tcsh"]);
    assert_eq!(r.code, Some(2), "{r:#?}");
    assert!(r.stdout.is_empty());
    assert!(r.stderr.contains("bash"), "{}", r.stderr);
}
