//! Replays every committed fuzz input through its target on stable Rust: the seed corpus
//! (`fuzz/corpus/<target>/`) and every crash found so far, minimised
//! (`fuzz/regressions/<target>/`). A failure names the file and the panic.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use penumbra::{Override, SceneFile, SceneFormat};
use penumbra_fuzz_targets::{assets_dir, decode_pack, repo_dir, TARGETS};

/// The files of `dir`, sorted; none when it does not exist.
fn files(dir: &Path) -> Vec<std::path::PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut files: Vec<_> = entries
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

#[test]
fn every_corpus_and_regression_input_passes_its_target() {
    let fuzz = repo_dir().join("fuzz");
    let mut failures = Vec::new();
    for target in &TARGETS {
        let corpus = files(&fuzz.join("corpus").join(target.name));
        assert!(
            !corpus.is_empty(),
            "no seed corpus for `{}` under {}",
            target.name,
            fuzz.display()
        );
        let regressions = files(&fuzz.join("regressions").join(target.name));
        for path in corpus.iter().chain(&regressions) {
            let bytes = std::fs::read(path).unwrap();
            if let Err(panic) = catch_unwind(AssertUnwindSafe(|| (target.run)(&bytes))) {
                let message = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                failures.push(format!("{}: {message}", path.display()));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The seed scenes build (their meshes and textures are found under `fuzz/assets/`): mutations
/// of them reach the builder and the renderer, not only the parser's errors.
#[test]
fn every_seed_scene_builds() {
    for (folder, format) in [
        ("scene_toml", SceneFormat::Toml),
        ("scene_json", SceneFormat::Json),
    ] {
        for path in files(&repo_dir().join("fuzz/corpus").join(folder)) {
            let text = std::fs::read_to_string(&path).unwrap();
            let file = SceneFile::from_str(&text, format, &path, assets_dir()).unwrap();
            if let Err(e) = file.build(1) {
                panic!("{}: {e}", path.display());
            }
        }
    }
    // The packs, from their packed files alone (none of them is on disk where they say).
    for path in files(&repo_dir().join("fuzz/corpus/pack")) {
        let pack = decode_pack(&std::fs::read(&path).unwrap());
        assert!(!pack.files.is_empty(), "{}", path.display());
        if let Err(e) = pack.load().and_then(|file| file.build(1)) {
            panic!("{}: {e}", path.display());
        }
    }
    // And with the override on their first line applied.
    for path in files(&repo_dir().join("fuzz/corpus/scene_override")) {
        let text = std::fs::read_to_string(&path).unwrap();
        let (first, rest) = text.split_once('\n').unwrap();
        let o = Override::parse(first).unwrap();
        let built = SceneFile::from_str_with(rest, SceneFormat::Toml, &path, assets_dir(), &[o])
            .and_then(|file| file.build(1));
        if let Err(e) = built {
            panic!("{}: {e}", path.display());
        }
    }
}
