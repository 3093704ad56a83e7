//! Scene-key overrides (`KEY.PATH=VALUE`, the CLI's `--set`) through the library: an override
//! is read like the same value written in the file (types, checks, messages), errors about it
//! name the override and its key instead of a line, and errors elsewhere keep their line.

mod support;

use std::path::Path;

use penumbra::{ErrorKind, Override, Sampler, SceneError, SceneFile, SceneFormat, SettingsPatch};
use support::{line_of, BASE_JSON, BASE_TOML as BASE};

fn load(text: &str, format: SceneFormat, set: &[&str]) -> Result<SceneFile, SceneError> {
    let set: Vec<Override> = set.iter().map(|s| Override::parse(s).unwrap()).collect();
    SceneFile::from_str_with(text, format, "s", ".", &set)
}

fn toml(set: &[&str]) -> Result<SceneFile, SceneError> {
    load(BASE, SceneFormat::Toml, set)
}

/// The error of loading and building with `set`, with its kind, key, override and line.
fn error(text: &str, format: SceneFormat, set: &[&str]) -> SceneError {
    match load(text, format, set) {
        Ok(file) => file.build(1).expect_err("the scene was accepted"),
        Err(e) => e,
    }
}

#[test]
fn overrides_change_the_description() {
    let file = toml(&[
        "film.width=64",
        "render.sampler=center",
        "render.seed = 9",
        "objects[1].material=\"red\"",
        "objects.0.corner=[-2, -0.5, 2]",
        "materials.red.diffuse=[0, 0, 1]",
    ])
    .unwrap();
    let d = &file.desc;
    assert_eq!(d.film.width, 64);
    assert_eq!(d.render.seed, Some(9));
    assert_eq!(d.render.sampler, Some(penumbra::Sampler::Center));
    assert_eq!(d.materials.0[0].1.diffuse.map(|c| c.rgb().z), Some(1.0));
    let scene = file.build(1).unwrap();
    assert_eq!(scene.settings.width, 64);
}

#[test]
fn seeds_beyond_tomls_integers_are_taken_as_the_seed_flag_takes_them() {
    let max = toml(&["render.seed=18446744073709551615"]).unwrap();
    assert_eq!(max.desc.render.seed, Some(u64::MAX));
    let quoted = toml(&["render.seed=\"42\""]).unwrap();
    assert_eq!(quoted.desc.render.seed, Some(42));
    for bad in ["18446744073709551616", "-1", "1.5", "\"12a\"", "\"\""] {
        let e = toml(&[&format!("render.seed={bad}")]).unwrap_err();
        assert!(e.to_string().contains("non-negative integer"), "{bad}: {e}");
    }
}

#[test]
fn a_later_override_wins_and_tables_are_created() {
    let file = toml(&["film.width=64", "film.width=32", "render.ambient=0.5"]).unwrap();
    assert_eq!(file.desc.film.width, 32);
    assert!(file.desc.render.ambient.is_some());
    // A whole table as an inline TOML value.
    let file = toml(&["camera={position=[0,0,9], look_at=[0,0,0], fov=30}"]).unwrap();
    let Some(penumbra::desc::CameraDesc::Still(camera)) = file.desc.camera else {
        panic!("not a still camera: {:?}", file.desc.camera);
    };
    let penumbra::desc::LensDesc::Fov(fov) = camera.lens else {
        panic!("a camera of fov: {camera:?}");
    };
    assert_eq!(fov.0, 30.0);
}

#[test]
fn every_shipped_scene_reads_the_same_through_the_override_path() {
    // Setting the film width to its own value must give exactly the description of the file
    // itself: the value tree (kept in file order) loses nothing the direct parse sees.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if SceneFormat::from_path(&path).is_none() {
            continue;
        }
        let plain = SceneFile::load(&path).unwrap();
        let width = format!("film.width={}", plain.desc.film.width);
        let set = [Override::parse(&width).unwrap()];
        let overridden = SceneFile::load_with(&path, &set).unwrap();
        assert_eq!(plain.desc, overridden.desc, "{}", path.display());
        seen += 1;
    }
    assert!(seen >= 5, "only {seen} scenes");
}

#[test]
fn json_scenes_take_overrides_and_keep_null_as_absent() {
    let file = load(BASE_JSON, SceneFormat::Json, &["film.height=7"]).unwrap();
    assert_eq!(file.desc.film.height, 7);
    let with_null = BASE_JSON.replace("\"height\": 12}", "\"height\": 12, \"gamma\": null}");
    let file = load(&with_null, SceneFormat::Json, &["film.width=5"]).unwrap();
    assert_eq!(file.desc.film.gamma, None);
    // A duplicate key is still refused, on its line.
    let dup = BASE_JSON.replace("\"height\": 12}", "\"height\": 12, \"width\": 3}");
    let e = error(&dup, SceneFormat::Json, &["film.width=5"]);
    assert!(e.to_string().contains("duplicate key `width`"), "{e}");
    assert_eq!(e.location().unwrap().line, Some(2));
}

/// Asserts `e` is about the override `set` at `key`, of `kind`, with `words` in its message.
fn assert_override_error(e: &SceneError, kind: ErrorKind, key: &str, set: &str, words: &[&str]) {
    let loc = e.location().expect("a located error");
    assert_eq!(e.kind(), kind, "{e}");
    assert_eq!(loc.key.as_deref(), Some(key), "{e}");
    assert_eq!(loc.set_by.as_deref(), Some(set), "{e}");
    assert_eq!(loc.line, None, "{e}");
    let text = e.to_string();
    assert!(text.contains(&format!("(--set {set})")), "{text}");
    for w in words {
        assert!(text.contains(w), "{text} lacks {w}");
    }
}

#[test]
fn a_bad_override_is_an_error_naming_it() {
    for format in [SceneFormat::Toml, SceneFormat::Json] {
        let text = if format == SceneFormat::Toml {
            BASE
        } else {
            BASE_JSON
        };
        let set = "film.width=wide";
        let e = error(text, format, &[set]);
        assert_override_error(
            &e,
            ErrorKind::BadValue,
            "film.width",
            set,
            &["expected an integer"],
        );

        let set = "film.widht=64";
        let e = error(text, format, &[set]);
        assert_override_error(
            &e,
            ErrorKind::UnknownKey,
            "film.widht",
            set,
            &["unknown field `widht`"],
        );

        let set = "render.sampler=fancy";
        let e = error(text, format, &[set]);
        assert_override_error(&e, ErrorKind::BadValue, "render.sampler", set, &["fancy"]);

        // Found while building: a name that refers to nothing, a value out of range.
        let set = "objects[1].material=blue";
        let e = error(text, format, &[set]);
        assert_override_error(
            &e,
            ErrorKind::UnknownName,
            "objects[1].material",
            set,
            &["blue"],
        );
        let set = "camera.fov=200";
        let e = error(text, format, &[set]);
        assert_override_error(&e, ErrorKind::BadValue, "camera.fov", set, &["fov"]);

        // A table the override made: what it lacks is the override's mistake too.
        let set = "cameras.top.fov=30";
        let e = error(text, format, &[set]);
        assert_override_error(&e, ErrorKind::MissingKey, "cameras.top", set, &["position"]);

        // A path the file's values cannot take.
        let set = "objects[5].material=red";
        let e = error(text, format, &[set]);
        assert_override_error(&e, ErrorKind::BadValue, "objects", set, &["2 entries"]);
        let set = "film.width.x=1";
        let e = error(text, format, &[set]);
        assert_override_error(&e, ErrorKind::BadValue, "film.width", set, &["not a table"]);
    }
}

#[test]
fn an_error_in_the_file_keeps_its_line_with_overrides() {
    let text = BASE.replace("fov = 45", "fov = 45\nzoom = 2");
    let e = error(&text, SceneFormat::Toml, &["film.width=64"]);
    let loc = e.location().unwrap();
    assert_eq!(e.kind(), ErrorKind::UnknownKey);
    assert_eq!(loc.set_by, None);
    assert_eq!(loc.line, Some(line_of(&text, "zoom")));
}

#[test]
fn malformed_overrides_are_refused_before_loading() {
    for bad in [
        "film.width",
        "=3",
        "film..width=3",
        "objects[x].material=red",
    ] {
        let e = Override::parse(bad).expect_err(bad);
        assert!(e.to_string().contains("KEY.PATH=VALUE"), "{e}");
    }
}

/// [`BASE`] rendering with `render` as its `[render]` table.
fn with_render(render: &str) -> String {
    format!("{BASE}\n[render]\n{render}\n")
}

/// The sampler and samples per pixel `text` builds with `set`.
fn sampling(text: &str, set: &[&str]) -> (Sampler, u32) {
    let scene = load(text, SceneFormat::Toml, set)
        .unwrap()
        .build(1)
        .unwrap();
    (scene.settings.sampler, scene.settings.spp)
}

#[test]
fn a_sampler_overridden_alone_takes_its_own_count_as_the_flag_does() {
    // The shipped rooms say rgss with 4 samples; a file saying center without a count gets 1.
    let text = with_render("sampler = \"rgss\"\nsamples = 16");
    assert_eq!(
        sampling(&text, &["render.sampler=center"]),
        (Sampler::Center, 1)
    );
    assert_eq!(
        sampling(&text, &["render.sampler=grid"]),
        (Sampler::Grid, 16)
    );
    let set = ["render.sampler=grid", "render.samples=9"];
    assert_eq!(sampling(&text, &set), (Sampler::Grid, 9));
    let set = ["render.samples=1", "render.sampler=center"];
    assert_eq!(sampling(&text, &set), (Sampler::Center, 1));
    // The command line's --sampler (a settings patch) gets the same counts from the same file.
    let file = load(&text, SceneFormat::Toml, &[]).unwrap();
    let scene = file.build(1).unwrap();
    for (sampler, spp) in [(Sampler::Center, 1), (Sampler::Grid, 16)] {
        let patch = SettingsPatch {
            sampler: Some(sampler),
            ..SettingsPatch::default()
        };
        let patched = patch.apply(&scene.settings, file.samples()).unwrap();
        assert_eq!((patched.sampler, patched.spp), (sampler, spp));
    }
    // A file without [render]: center alone is 1, as a file saying center without samples.
    assert_eq!(
        sampling(BASE, &["render.sampler=center"]),
        (Sampler::Center, 1)
    );
    let text = with_render("sampler = \"center\"");
    assert_eq!(sampling(&text, &[]), (Sampler::Center, 1));
}

#[test]
fn center_with_a_count_above_1_is_refused_naming_who_said_it() {
    let text = with_render("sampler = \"rgss\"\nsamples = 4");
    for set in [
        ["render.sampler=center", "render.samples=4"],
        ["render.samples=4", "render.sampler=center"],
    ] {
        let e = error(&text, SceneFormat::Toml, &set);
        let words = ["center sampler takes exactly 1 sample"];
        assert_override_error(
            &e,
            ErrorKind::BadValue,
            "render.samples",
            "render.samples=4",
            &words,
        );
    }
    // A file that says both keeps its line, overrides or not.
    let text = with_render("sampler = \"center\"\nsamples = 4");
    let e = error(&text, SceneFormat::Toml, &["film.width=8"]);
    let loc = e.location().unwrap();
    assert_eq!(
        (loc.set_by.as_deref(), loc.key.as_deref()),
        (None, Some("render.samples"))
    );
    assert_eq!(loc.line, Some(line_of(&text, "samples = 4")));
    // An override of the count alone against the file's center names the override.
    let text = with_render("sampler = \"center\"");
    let e = error(&text, SceneFormat::Toml, &["render.samples=4"]);
    let words = ["center sampler"];
    assert_override_error(
        &e,
        ErrorKind::BadValue,
        "render.samples",
        "render.samples=4",
        &words,
    );
}
