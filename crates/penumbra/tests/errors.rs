//! Scene-file errors (SPEC §8, docs/spec.md) through the library, as one table. Each row is a
//! bad scene (TOML, plus its JSON twin where JSON's own location handling is at stake: syntax
//! errors, unknown keys, wrong types, unknown names, elements of nested arrays) with what the
//! error must say:
//!
//! - the stage that rejects it: parsing (`SceneFile::from_str`: types, finiteness, option
//!   names, which keys each table takes) or building (`SceneFile::build`: ranges, names that
//!   refer to other entries, the files a scene loads);
//! - its [`ErrorKind`];
//! - its line and column, computed from the scene text by finding a needle in it;
//! - its key path (`objects[1].material`), or none for errors about the whole file;
//! - words its message must contain (case-insensitive).
//!
//! Where errors point, by stage and format:
//! - TOML, parsing: where toml's span puts it: the offending value, or the key of an unknown
//!   key in a plain table, or the header of a table that lacks a key;
//! - JSON, parsing: where serde_json stopped reading: the last character of the offending
//!   token (the opening bracket for an array), or the closing brace of an object that lacks a
//!   key;
//! - both formats, building: the first character of the key the error is about.
//!
//! Columns count characters, not bytes. Every mismatch of every row is reported at once.

mod support;

use std::path::Path;

use penumbra::{AssetKind, ErrorKind, SceneError, SceneFile, SceneFormat};
use support::{
    edit, nth_position_of, with_mesh, with_texture, TempDir, BASE_JSON, BASE_TOML as BASE,
};

use ErrorKind::{BadValue, MissingKey, Syntax, UnknownKey, UnknownName};
const MESH: ErrorKind = ErrorKind::Asset(AssetKind::Mesh);
const IMAGE: ErrorKind = ErrorKind::Asset(AssetKind::Image);

// ---------------------------------------------------------------------------------------------
// The table
// ---------------------------------------------------------------------------------------------

/// Every bad scene and what its error must be. Laid out as a table, one row per scene:
/// `toml|json(name, text)[.file(path, contents)...].parse_error|build_error(kind, where, key,
/// words)`.
#[rustfmt::skip]
fn table() -> Vec<Case> {
    let mut rows = vec![
        // --- Unknown keys, at every level (parsing) ---
        toml("unknown key at the top level", format!("colour = 1\n{BASE}"))
            .parse_error(UnknownKey, at("colour"), Some("colour"), &["unknown", "colour"]),
        toml("unknown table at the top level", edit(BASE, "[camera]", "[camra]"))
            .parse_error(UnknownKey, at("camra"), Some("camra"), &["unknown", "camra"]),
        toml("unknown key in [film]", edit(BASE, "height = 12\n", "height = 12\nwidht = 3\n"))
            .parse_error(UnknownKey, at("widht"), Some("film.widht"), &["unknown", "widht"]),
        toml("unknown key in [camera]", edit(BASE, "fov = 45\n", "fov = 45\nfvo = 3\n"))
            .parse_error(UnknownKey, at("fvo"), Some("camera.fvo"), &["unknown", "fvo"]),
        toml("unknown key in [cameras.NAME]",
             edit(&named_camera(BASE), "fov = 45\n", "fov = 45\nlookat = 1\n"))
            .parse_error(UnknownKey, at("lookat"), Some("cameras.front.lookat"), &["unknown", "lookat"]),
        toml("unknown key in [render]", with_render("sampels = 4"))
            .parse_error(UnknownKey, at("sampels"), Some("render.sampels"), &["unknown", "sampels"]),
        toml("unknown key in [materials.NAME]",
             edit(BASE, "specular = 0.3\n", "specular = 0.3\ndifuse = 1\n"))
            .parse_error(UnknownKey, at("difuse"), Some("materials.red.difuse"), &["unknown", "difuse"]),
        // Tables with a `type` point at the value of an unknown key, not at the key.
        toml("unknown key in [textures.NAME]",
             format!("{BASE}\n[textures.board]\ntype = \"checker\"\ncolour = 1\n"))
            .parse_error(UnknownKey, value_of("colour = 1"), Some("textures.board.colour"),
                         &["unknown", "colour", "checker texture"]),
        toml("unknown key in [[lights]]",
             edit(BASE, "position = [0, 5, 5]\n", "position = [0, 5, 5]\ncolour = 1\n"))
            .parse_error(UnknownKey, value_of("colour = 1"), Some("lights[0].colour"),
                         &["unknown", "colour", "point light"]),
        toml("unknown key in [[objects]]", edit(BASE, "size = 1\n", "size = 1\ncolor = [1, 0, 0]\n"))
            .parse_error(UnknownKey, value_of("color = [1, 0, 0]"), Some("objects[1].color"),
                         &["unknown", "color", "cube"]),

        // --- Keys of another kind of object, light or texture (parsing) ---
        // The message says what the kind takes.
        toml("key of another object kind", edit(BASE, "size = 1\n", "size = 1\nradius = 2\n"))
            .parse_error(UnknownKey, value_of("radius = 2"), Some("objects[1].radius"),
                         &["radius", "cube", "(it takes: center, size, name, material, scale, rotate, translate, matrix)"]),
        toml("key of another light kind",
             edit(BASE, "position = [0, 5, 5]\n", "position = [0, 5, 5]\ncenter = [0, 1, 0]\n"))
            .parse_error(UnknownKey, value_of("center = [0, 1, 0]"), Some("lights[0].center"),
                         &["center", "point light", "(it takes: position, color, intensity)"]),
        toml("key of another texture kind",
             format!("{BASE}\n[textures.board]\ntype = \"checker\"\nfile = \"b.png\"\n"))
            .parse_error(UnknownKey, value_of("file = \"b.png\""), Some("textures.board.file"),
                         &["file", "checker texture", "(it takes: even, odd, checks, uv_scale, uv_offset)"]),
        // `radius` is a key some objects take, so it is wrong only once `type` says "cube":
        // reported at the table, whose keys are all read by then.
        toml("type after a key of another object kind",
             edit(BASE, CUBE, "material = \"red\"\nradius = 1\ntype = \"cube\"\n"))
            .parse_error(UnknownKey, at_nth("[[objects]]", 1), Some("objects[1]"), &["radius", "cube"]),
        toml("type after a key of another light kind",
             edit(BASE, POINT_LIGHT, "position = [0, 5, 5]\ncenter = [0, 1, 0]\ntype = \"point\"\n"))
            .parse_error(UnknownKey, at("[[lights]]"), Some("lights[0]"), &["center", "point light"]),
        // Before `type`, a key no kind takes: the hint lists the keys of every kind.
        toml("unknown key before type in [[lights]]",
             edit(BASE, POINT_LIGHT, "colour = 1\ntype = \"point\"\nposition = [0, 5, 5]\n"))
            .parse_error(UnknownKey, value_of("colour = 1"), Some("lights[0].colour"),
                         &["unknown key `colour` (an area light takes: center, u, v, samples, jitter, color, intensity; a point light takes: position, color, intensity; an environment light takes: file, rotation, samples, visible, color, intensity; a directional light takes: direction, angle, samples, color, intensity; a spot light takes: position, direction, inner_angle, outer_angle, color, intensity)"]),
        toml("unknown object type", edit(BASE, "type = \"cube\"", "type = \"cylinder\""))
            .parse_error(BadValue, value_of("type = \"cylinder\""), Some("objects[1].type"),
                         &["cylinder", "sphere"]),
        toml("unknown light type", edit(BASE, "type = \"point\"", "type = \"laser\""))
            .parse_error(BadValue, value_of("type = \"laser\""), Some("lights[0].type"),
                         &["laser", "area", "environment", "spot"]),
        toml("unknown texture type", format!("{BASE}\n[textures.t]\ntype = \"noise\"\n"))
            .parse_error(BadValue, value_of("type = \"noise\""), Some("textures.t.type"),
                         &["noise", "checker"]),

        // --- Wrong types (parsing), in the user's words ("integer", not Rust's "i64") ---
        toml("string for an integer", edit(BASE, "width = 16", "width = \"16\""))
            .parse_error(BadValue, value_of("width = \"16\""), Some("film.width"),
                         &["string", "expected an integer"]),
        toml("fraction for an integer", edit(BASE, "width = 16", "width = 1.5"))
            .parse_error(BadValue, value_of("width = 1.5"), Some("film.width"), &["1.5", "integer"]),
        toml("string for a number or vector", edit(BASE, "size = 1", "size = \"big\""))
            .parse_error(BadValue, value_of("size = \"big\""), Some("objects[1].size"),
                         &["string", "number"]),
        toml("negative seed", with_render("seed = -1"))
            .parse_error(BadValue, value_of("seed = -1"), Some("render.seed"),
                         &["-1", "non-negative integer"]),
        toml("vector of two numbers", edit(BASE, "position = [0, 1, 5]", "position = [0, 1]"))
            .parse_error(BadValue, value_of("position = [0, 1]"), Some("camera.position"),
                         &["length 2", "3"]),
        // serde's own fixed arrays stop after N elements and TOML dropped the rest silently.
        toml("vector of four numbers", edit(BASE, "position = [0, 1, 5]", "position = [0, 1, 5, 6]"))
            .parse_error(BadValue, value_of("position = [0, 1, 5, 6]"), Some("camera.position"),
                         &["length 4", "3"]),
        toml("triangle with four vertices",
             with_triangle("[0, 1, 0], [1, 1, 0]"))
            .parse_error(BadValue, value_of("vertices = [[0, 0, 0]"), Some("objects[2].vertices"),
                         &["length 4", "3"]),
        toml("uv with three numbers",
             format!("{}uvs = [[0, 0, 9], [1, 0], [0, 1]]\n", with_triangle("[0, 1, 0]")))
            .parse_error(BadValue, at("[0, 0, 9]"), Some("objects[2].uvs[0]"),
                         &["length 3", "2"]),
        toml("string in a vector", edit(BASE, "position = [0, 1, 5]", "position = [0, \"1\", 5]"))
            .parse_error(BadValue, at("\"1\""), Some("camera.position[1]"), &["string", "number"]),
        toml("string deep in a triangle's vertices", with_triangle("[0, \"y\", 0]"))
            .parse_error(BadValue, at("\"y\""), Some("objects[2].vertices[2][1]"), &["string", "number"]),
        toml("an object that is not a table",
             format!("objects = [\"cube\"]\n{}", before(BASE, "[[objects]]")))
            .parse_error(BadValue, at("\"cube\""), Some("objects[0]"), &["string", "table"]),

        // --- Numbers the renderer cannot hold (parsing) ---
        toml("infinite number", edit(BASE, "fov = 45", "fov = inf"))
            .parse_error(BadValue, value_of("fov = inf"), Some("camera.fov"), &["inf", "finite"]),
        // The key path names the element, but the position is the vector's: the check runs
        // once toml has handed the element over, so the error gets the array's span.
        toml("NaN in a vector", edit(BASE, "position = [0, 1, 5]", "position = [0, nan, 5]"))
            .parse_error(BadValue, value_of("position = [0, nan"), Some("camera.position[1]"),
                         &["nan", "finite"]),
        // Colors take a plain number too, through another code path.
        toml("infinite color", edit(BASE, "specular = 0.3", "specular = -inf"))
            .parse_error(BadValue, value_of("specular = -inf"), Some("materials.red.specular"),
                         &["-inf", "finite"]),
        // Finite as f64 but infinite once the renderer stores them as f32. At the vector, as
        // for NaN above.
        toml("number beyond f32 in a vector", edit(BASE, "position = [0, 1, 5]", "position = [0, 1e39, 5]"))
            .parse_error(BadValue, value_of("position = [0, 1e39"), Some("camera.position[1]"),
                         &["out of range"]),
        toml("number beyond f32 as a color", edit(BASE, "specular = 0.3", "specular = 1e300"))
            .parse_error(BadValue, value_of("specular = 1e300"), Some("materials.red.specular"),
                         &["out of range"]),
        toml("number beyond f64", edit(BASE, "fov = 45", "fov = 1e999"))
            .parse_error(BadValue, value_of("fov = 1e999"), Some("camera.fov"), &["overflow"]),

        // --- Names of options (parsing); the message lists the valid ones ---
        toml("unknown sampler", with_render("sampler = \"random\""))
            .parse_error(BadValue, value_of("sampler = \"random\""), Some("render.sampler"),
                         &["random", "jittered"]),
        toml("unknown shading", with_render("shading = \"flat\""))
            .parse_error(BadValue, value_of("shading = \"flat\""), Some("render.shading"),
                         &["flat", "blinn-phong"]),
        toml("unknown light model", with_render("light_model = \"pbr\""))
            .parse_error(BadValue, value_of("light_model = \"pbr\""), Some("render.light_model"),
                         &["pbr", "physical"]),
        toml("unknown filter", with_image_option("filter = \"cubic\""))
            .parse_error(BadValue, value_of("filter = \"cubic\""), Some("textures.t.filter"),
                         &["cubic", "bilinear"]),
        toml("unknown wrap", with_image_option("wrap = \"mirror\""))
            .parse_error(BadValue, value_of("wrap = \"mirror\""), Some("textures.t.wrap"),
                         &["mirror", "clamp"]),
        toml("unknown colorspace", with_image_option("colorspace = \"rgb\""))
            .parse_error(BadValue, value_of("colorspace = \"rgb\""), Some("textures.t.colorspace"),
                         &["rgb", "linear"]),

        // --- Missing keys (parsing): at the table that lacks them ---
        toml("missing film.width", edit(BASE, "width = 16\n", ""))
            .parse_error(MissingKey, at("[film]"), Some("film"), &["missing", "width"]),
        toml("missing camera.position", edit(BASE, "position = [0, 1, 5]\n", ""))
            .parse_error(MissingKey, at("[camera]"), Some("camera"), &["missing", "position"]),
        toml("missing center of a cube", edit(BASE, "center = [0, 0, 0]\n", ""))
            .parse_error(MissingKey, at_nth("[[objects]]", 1), Some("objects[1]"), &["missing", "center"]),
        toml("missing type of an object", edit(BASE, "type = \"cube\"\n", ""))
            .parse_error(MissingKey, at_nth("[[objects]]", 1), Some("objects[1]"), &["missing", "type"]),
        toml("missing position of a light", edit(BASE, "position = [0, 5, 5]\n", ""))
            .parse_error(MissingKey, at("[[lights]]"), Some("lights[0]"), &["missing", "position"]),
        toml("missing file of an image texture", format!("{BASE}\n[textures.t]\ntype = \"image\"\n"))
            .parse_error(MissingKey, at("[textures.t]"), Some("textures.t"), &["missing", "file"]),
        // Nothing to point at but the file itself.
        toml("no [film] table", edit(BASE, "[film]\nwidth = 16\nheight = 12\n", ""))
            .parse_error(MissingKey, FileStart, None, &["missing", "film"]),
        toml("empty file", "")
            .parse_error(MissingKey, FileStart, None, &["missing", "film"]),

        // --- Names that refer to nothing (building); the message lists those that exist ---
        toml("unknown material", edit(BASE, "material = \"red\"", "material = \"rde\""))
            .build_error(UnknownName, at("material = "), Some("objects[1].material"),
                         &["unknown material", "\"rde\"", "known: red"]),
        toml("unknown texture, none defined", with_material_texture(BASE, "wood"))
            .build_error(UnknownName, at("texture = "), Some("materials.red.texture"),
                         &["unknown texture", "\"wood\"", "none are defined"]),
        toml("unknown texture, others defined",
             format!("{}\n[textures.board]\ntype = \"checker\"\n", with_material_texture(BASE, "wood")))
            .build_error(UnknownName, at("texture = "), Some("materials.red.texture"),
                         &["unknown texture", "\"wood\"", "known: board"]),

        // --- Values out of range (building): at the key ---
        toml("samples not a perfect square", with_render("samples = 3"))
            .build_error(BadValue, at("samples = 3"), Some("render.samples"), &["perfect square", "not 3"]),
        // Finite numbers whose products overflow f32 (issue 10, class 2): refused at the key
        // rather than rendered as infinite or NaN pixels.
        toml("light color × intensity beyond f32",
             edit(BASE, "position = [0, 5, 5]\n",
                  "position = [0, 5, 5]\ncolor = [3e38, 3e38, 3e38]\nintensity = 10\n"))
            .build_error(BadValue, at("intensity = 10"), Some("lights[0].intensity"),
                         &["color × intensity", "3e39", "at most"]),
        toml("light intensity near f32::MAX",
             edit(BASE, "position = [0, 5, 5]\n", "position = [0, 5, 5]\nintensity = 3e38\n"))
            .build_error(BadValue, at("intensity = 3e38"), Some("lights[0].intensity"),
                         &["color × intensity", "3e38", "at most"]),
        toml("lights that together emit beyond the range",
             edit(BASE, "position = [0, 5, 5]\n",
                  "position = [0, 5, 5]\nintensity = 6e31\n\n[[lights]]\ntype = \"point\"\n\
                   position = [0, 5, 4]\nintensity = 5e31\n"))
            .build_error(BadValue, at("intensity = 5e31"), Some("lights[1].intensity"),
                         &["lights together", "1.1e32", "at most"]),
        toml("ambient light beyond the range", with_render("ambient = [1, 2e38, 1]"))
            .build_error(BadValue, at("ambient = "), Some("render.ambient"), &["2e38", "at most"]),
        toml("background beyond the range", with_render("background = 3e38"))
            .build_error(BadValue, at("background = "), Some("render.background"), &["3e38", "at most"]),
        toml("diffuse near f32::MAX",
             edit(BASE, "diffuse = [0.8, 0.1, 0.1]", "diffuse = [3.4e38, 0.1, 0.1]"))
            .build_error(BadValue, at("diffuse = "), Some("materials.red.diffuse"),
                         &["reflect", "at most"]),
        toml("ambient × the ambient light beyond the range",
             with_render("ambient = [1e30, 1e30, 1e30]").replace("specular = 0.3\n", "specular = 0.3\nambient = 1e10\n"))
            .build_error(BadValue, at("ambient = 1e10"), Some("materials.red.ambient"),
                         &["reflect", "1e40", "at most"]),
        toml("checker color × diffuse beyond the range",
             format!("{}\n[textures.board]\ntype = \"checker\"\nodd = 1e30\n",
                     with_material_texture(&edit(BASE, "diffuse = [0.8, 0.1, 0.1]", "diffuse = 1e10"), "board")))
            .build_error(BadValue, at("diffuse = 1e10"), Some("materials.red.diffuse"),
                         &["reflect", "at most"]),
        toml("zero samples", with_render("samples = 0"))
            .build_error(BadValue, at("samples = 0"), Some("render.samples"), &["perfect square", "not 0"]),
        toml("center sampler with 4 samples", with_render("sampler = \"center\"\nsamples = 4"))
            .build_error(BadValue, at("samples = 4"), Some("render.samples"), &["center", "exactly 1"]),
        toml("camera looking at itself", edit(BASE, "look_at = [0, 0, 0]", "look_at = [0, 1, 5]"))
            .build_error(BadValue, at("look_at"), Some("camera.look_at"), &["degenerate"]),
        // Looking straight down with up = +y: no way to tell right from left.
        toml("camera looking along up", edit(BASE, "look_at = [0, 0, 0]", "look_at = [0, -3, 5]"))
            .build_error(BadValue, at("look_at"), Some("camera.look_at"), &["degenerate", "parallel"]),
        // Every camera is checked, not only the one rendered: the file is wrong either way.
        toml("degenerate named camera that is not rendered",
             format!("{}\n[cameras.top]\n{TOP_CAMERA}", named_camera(BASE)))
            .build_error(BadValue, at_nth("look_at", 1), Some("cameras.top.look_at"), &["degenerate"]),
        toml("both [camera] and [cameras.NAME]", format!("{BASE}\n[cameras.side]\n{SIDE_CAMERA}"))
            .build_error(BadValue, at("cameras.side"), Some("cameras"), &["either", "not both"]),
        toml("no camera", without_camera(BASE))
            .build_error(MissingKey, FileStart, None, &["missing", "camera"]),

        // --- Camera paths (building; a path's shape when parsing) ---
        toml("camera keys out of frame order",
             format!("{}\n[cameras.fly]\n{}", named_camera(BASE), keys(&[10, 5])))
            .build_error(BadValue, at("frame = 5"), Some("cameras.fly.keys[1].frame"),
                         &["frame 5", "after frame 10", "order"]),
        toml("two camera keys of one frame",
             format!("{}\n[cameras.fly]\n{}", named_camera(BASE), keys(&[3, 10, 10])))
            .build_error(BadValue, at_nth("frame = 10", 1), Some("cameras.fly.keys[2].frame"),
                         &["frame 10", "keys[1]"]),
        toml("camera path without keys",
             format!("{}\n[cameras.fly]\nfov = 40\nkeys = []\n", named_camera(BASE)))
            .build_error(BadValue, at("keys"), Some("cameras.fly.keys"), &["at least one key"]),
        toml("a key without fov", format!("{}\n[cameras.fly]\n{}", named_camera(BASE),
                                          keys(&[1, 2]).replacen("fov = 40\n", "", 1)))
            .build_error(MissingKey, at_nth("[[cameras.fly.keys]]", 0), Some("cameras.fly.keys[0]"),
                         &["missing", "fov"]),
        toml("orbit of 0 frames",
             format!("{}\n[cameras.turn]\nfov = 40\npath = {{ type = \"orbit\", center = [0, 0, 0], radius = 4, frames = 0 }}\n",
                     named_camera(BASE)))
            .build_error(BadValue, at("frames = 0"), Some("cameras.turn.path.frames"),
                         &["from 1", "not 0"]),
        toml("orbit of an unknown kind",
             format!("{}\n[cameras.turn]\nfov = 40\npath = {{ type = \"spiral\", center = [0, 0, 0], radius = 4, frames = 8 }}\n",
                     named_camera(BASE)))
            .parse_error(BadValue, value_of("type = \"spiral\""), Some("cameras.turn.path.type"),
                         &["spiral", "orbit"]),
        toml("keys and a path",
             format!("{}\n[cameras.fly]\npath = {{ type = \"orbit\", center = [0, 0, 0], radius = 4, frames = 8 }}\n{}",
                     named_camera(BASE), keys(&[1, 2])))
            .parse_error(BadValue, at("[cameras.fly]"), Some("cameras.fly"), &["keys or a path"]),
        toml("zero scale", edit(BASE, "size = 1\n", "size = 1\nscale = 0\n"))
            .build_error(BadValue, at("scale"), Some("objects[1].scale"), &["scale", "zero"]),
        toml("zero scale along one axis", edit(BASE, "size = 1\n", "size = 1\nscale = [1, 0, 1]\n"))
            .build_error(BadValue, at("scale"), Some("objects[1].scale"), &["scale", "zero"]),
        // Not zero, but its inverse overflows (1e30) or its determinant underflows (1e-20).
        toml("huge scale", edit(BASE, "size = 1\n", "size = 1\nscale = 1e30\n"))
            .build_error(BadValue, at("scale"), Some("objects[1].scale"), &["scale", "32-bit", "1e38"]),
        toml("tiny scale", edit(BASE, "size = 1\n", "size = 1\nscale = 1e-20\n"))
            .build_error(BadValue, at("scale"), Some("objects[1].scale"), &["scale", "32-bit", "1e-38"]),
        toml("negative size", edit(BASE, "size = 1", "size = -1"))
            .build_error(BadValue, at("size"), Some("objects[1].size"), &["size", "negative"]),
        toml("negative size along one axis", edit(BASE, "size = 1", "size = [1, -1, 1]"))
            .build_error(BadValue, at("size"), Some("objects[1].size"), &["size", "negative"]),
        toml("negative radius", edit(BASE, CUBE, "type = \"sphere\"\ncenter = [0, 0, 0]\nradius = -1\n"))
            .build_error(BadValue, at("radius"), Some("objects[1].radius"), &["radius", "negative"]),
        toml("zero gamma", edit(BASE, "height = 12\n", "height = 12\ngamma = 0\n"))
            .build_error(BadValue, at("gamma"), Some("film.gamma"), &["gamma", "positive", "not 0"]),
        toml("negative gamma", edit(BASE, "height = 12\n", "height = 12\ngamma = -2.2\n"))
            .build_error(BadValue, at("gamma"), Some("film.gamma"), &["gamma", "positive", "not -2.2"]),
        // film.output is part of the scene file: checked even when the caller writes elsewhere.
        toml("unknown output format", edit(BASE, "height = 12\n", "height = 12\noutput = \"out.bmp\"\n"))
            .build_error(BadValue, at("output"), Some("film.output"), &["\"out.bmp\"", ".png"]),
        toml("zero light samples", with_render("light_samples = 0"))
            .build_error(BadValue, at("light_samples"), Some("render.light_samples"),
                         &["between 1 and 1024", "not 0"]),
        toml("too many samples of an area light",
             edit(BASE, POINT_LIGHT, &format!("{AREA_LIGHT}samples = 2000\n")))
            .build_error(BadValue, at("samples"), Some("lights[0].samples"),
                         &["between 1 and 1024", "not 2000"]),
        toml("resolution too large for memory",
             edit(BASE, "width = 16\nheight = 12", "width = 100000\nheight = 100000"))
            .build_error(BadValue, at("width"), Some("film.width"), &["too large", "100000x100000"]),
        toml("zero width", edit(BASE, "width = 16", "width = 0"))
            .build_error(BadValue, at("width"), Some("film.width"), &["at least 1", "not 0"]),
        toml("negative height", edit(BASE, "height = 12", "height = -1"))
            .build_error(BadValue, at("height"), Some("film.height"), &["at least 1", "not -1"]),
        toml("negative shininess", edit(BASE, "specular = 0.3", "shininess = -1"))
            .build_error(BadValue, at("shininess"), Some("materials.red.shininess"),
                         &["shininess", "at least 0"]),

        // --- Columns count characters, not bytes ("ø" is two bytes) ---
        toml("column after a non-ASCII name, parsing",
             edit(BASE, RED, "[materials]\n\"rød\" = { diffuse = \"x\" }\n"))
            .parse_error(BadValue, value_of("diffuse = \"x\""), Some("materials.rød.diffuse"), &["string"]),
        toml("column after a non-ASCII name, building",
             edit(BASE, RED, "[materials]\n\"rød\" = { shininess = -1 }\n"))
            .build_error(BadValue, at("shininess"), Some("materials.rød.shininess"), &["shininess"]),

        // --- TOML syntax, duplicates included: the parser's own position, no key path ---
        // toml's wording is its own: these check where, not what.
        toml("TOML: two equals signs", edit(BASE, "fov = 45", "fov = = 45"))
            .parse_error(Syntax, at("= 45"), None, &[]),
        toml("TOML: one closing bracket too many", edit(BASE, "look_at = [0, 0, 0]", "look_at = [0, 0, 0]]"))
            .parse_error(Syntax, end_of("[0, 0, 0]]"), None, &[]),
        // toml reads `45 45` as one unquoted string and points at its start.
        toml("TOML: two values", edit(BASE, "fov = 45", "fov = 45 45"))
            .parse_error(Syntax, at("45 45"), None, &[]),
        toml("TOML: unclosed table header", edit(BASE, "[materials.red]", "[materials.red"))
            .parse_error(Syntax, after("[materials.red"), None, &[]),
        // Duplicates and nesting too deep name their key path, found from the text.
        toml("TOML: duplicate key", edit(BASE, "size = 1", "size = 1\nsize = 2"))
            .parse_error(Syntax, at("size = 2"), Some("objects[1].size"), &["duplicate key `size`"]),
        // A second [materials.red] names the same material twice: at the repeated name.
        toml("TOML: duplicate material name", format!("{BASE}\n[materials.red]\ndiffuse = 1\n"))
            .parse_error(Syntax, at_nth("red]", 1), Some("materials.red"), &["duplicate key `red`"]),
        toml("TOML: duplicate key in a dotted key",
             edit(BASE, "fov = 45\n", "fov = 45\n\n[render]\nambient = 0.1\n\"ambient\" = 0.2\n"))
            .parse_error(Syntax, at("\"ambient\" = 0.2"), Some("render.ambient"), &["duplicate key `ambient`"]),
        toml("TOML: nesting too deep",
             edit(BASE, "fov = 45", &format!("fov = {}{}", "[".repeat(200), "]".repeat(200))))
            .parse_error(Syntax, line_only("fov = [[["), Some("camera.fov"), &["nested too deeply"]),
        // A table header 200 keys deep: the parser says only "recursion limit".
        toml("TOML: table header nested too deep", format!("{BASE}\n[deep.{}x]\ny = 1\n", "a.".repeat(200)))
            .parse_error(Syntax, at("[deep."), Some(format!("deep.{}x", "a.".repeat(200)).leak()), &["nested too deeply"]),

        // --- Files the scene loads (building), written next to it: at the `file` key ---
        toml("missing mesh file", with_mesh("meshes/nosuch.obj"))
            .build_error(MESH, at("file ="), Some("objects[2].file"), &["cannot load mesh", "nosuch.obj"]),
        toml("OBJ index out of range", with_mesh("bad.obj"))
            .file("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
            .build_error(MESH, at("file ="), Some("objects[2].file"), &["bad.obj", "line 4"]),
        toml("corrupt OBJ file", with_mesh("bad.obj"))
            .file("bad.obj", "v 0 0 0\nv 1 0 zero\nv 0 1 0\nf 1 2 3\n")
            .build_error(MESH, at("file ="), Some("objects[2].file"), &["bad.obj", "line 2"]),
        // Files that are not OBJ or MTL text (issue 10, class 4): not an empty mesh that renders.
        toml("PNG given as an OBJ", with_mesh("m.obj"))
            .file("m.obj", PNG_START)
            .build_error(MESH, at("file ="), Some("objects[2].file"), &["m.obj", "not an OBJ", "PNG"]),
        toml("binary garbage given as an OBJ", with_mesh("m.obj"))
            .file("m.obj", (0..4096u32).map(|i| (i * 7919 % 251) as u8).collect::<Vec<u8>>())
            .build_error(MESH, at("file ="), Some("objects[2].file"), &["m.obj", "not an OBJ", "binary"]),
        toml("OBJ without faces", with_mesh("m.obj"))
            .file("m.obj", "# vertices only\nv 0 0 0\nv 1 0 0\nv 0 1 0\n")
            .build_error(MESH, at("file ="), Some("objects[2].file"), &["m.obj", "no faces"]),
        toml("text that is not an OBJ", with_mesh("m.obj"))
            .file("m.obj", "Dear user,\nthis is a letter, not a mesh.\n")
            .build_error(MESH, at("file ="), Some("objects[2].file"), &["m.obj", "no faces"]),
        toml("PNG given as an MTL", with_mesh("m.obj"))
            .file("m.obj", format!("mtllib m.mtl\n{TRIANGLE_OBJ}"))
            .file("m.mtl", PNG_START)
            .build_error(MESH, at("file ="), Some("objects[2].file"), &["m.mtl", "not an MTL", "PNG"]),
        toml("missing MTL file", with_mesh("m.obj"))
            .file("m.obj", format!("mtllib gone.mtl\n{TRIANGLE_OBJ}"))
            .build_error(MESH, at("file ="), Some("objects[2].file"), &["m.obj", "gone.mtl"]),
        toml("missing map_Kd texture", with_mesh("m.obj"))
            .file("m.obj", format!("mtllib m.mtl\nusemtl m\n{TRIANGLE_OBJ}"))
            .file("m.mtl", "newmtl m\nmap_Kd gone.png\n")
            .build_error(IMAGE, at("file ="), Some("objects[2].file"), &["map_Kd", "gone.png"]),
        toml("missing texture file", with_texture("textures/nosuch.png"))
            .build_error(IMAGE, at("file ="), Some("textures.wood.file"),
                         &["cannot load texture", "nosuch.png"]),
        toml("corrupt texture file", with_texture("textures/wood.png"))
            .file("textures/wood.png", "this is not a PNG file")
            .build_error(IMAGE, at("file ="), Some("textures.wood.file"),
                         &["cannot load texture", "wood.png"]),

        // -----------------------------------------------------------------------------------
        // JSON. Parsing errors are where serde_json stopped reading (see the module docs);
        // building errors are at the key's opening quote, as in TOML at the key.
        // -----------------------------------------------------------------------------------
        json("JSON: unknown key at the top level",
             edit(BASE_JSON, "{\n  \"film\"", "{\n  \"colour\": 1,\n  \"film\""))
            .parse_error(UnknownKey, end_of("\"colour\""), Some("colour"), &["unknown", "colour"]),
        json("JSON: unknown key in film", edit(BASE_JSON, "\"height\": 12}", "\"height\": 12, \"widht\": 3}"))
            .parse_error(UnknownKey, end_of("\"widht\""), Some("film.widht"), &["unknown", "widht"]),
        json("JSON: key of another object kind",
             edit(BASE_JSON, "\"size\": 1}", "\"size\": 1, \"radius\": 2}"))
            .parse_error(UnknownKey, end_of("\"radius\": 2"), Some("objects[1].radius"), &["radius", "cube"]),
        // An array value: serde_json stops at its opening bracket.
        json("JSON: key of another light kind",
             edit(BASE_JSON, "\"position\": [0, 5, 5]}", "\"position\": [0, 5, 5], \"center\": [0, 1, 0]}"))
            .parse_error(UnknownKey, value_of("\"center\": [0, 1, 0]"), Some("lights[0].center"),
                         &["center", "point light"]),
        json("JSON: unknown key in a point light, with the keys it takes",
             edit(BASE_JSON, "\"position\": [0, 5, 5]}", "\"position\": [0, 5, 5], \"colour\": [1, 0, 0]}"))
            .parse_error(UnknownKey, value_of("\"colour\": [1, 0, 0]"), Some("lights[0].colour"),
                         &["unknown key `colour` for a point light (it takes: position, color, intensity)"]),
        json("JSON: unknown key before type",
             edit(BASE_JSON, "{\"type\": \"point\"", "{\"colour\": [1, 0, 0], \"type\": \"point\""))
            .parse_error(UnknownKey, value_of("\"colour\": [1, 0, 0]"), Some("lights[0].colour"),
                         &["(an area light takes: center, u, v, samples, jitter, color, intensity; a point light takes: position, color, intensity; an environment light takes: file, rotation, samples, visible, color, intensity; a directional light takes: direction, angle, samples, color, intensity; a spot light takes: position, direction, inner_angle, outer_angle, color, intensity)"]),
        json("JSON: key of another object kind, with the keys it takes",
             edit(BASE_JSON, "\"size\": 1}", "\"size\": 1, \"file\": [1]}"))
            .parse_error(UnknownKey, value_of("\"file\": [1]"), Some("objects[1].file"),
                         &["(it takes: center, size, name, material, scale, rotate, translate, matrix)"]),
        // Found once the object is read: at its closing brace, like a missing key.
        json("JSON: type after a key of another object kind",
             edit(BASE_JSON, CUBE_JSON, "{\"material\": \"red\", \"radius\": 1, \"type\": \"cube\"}"))
            .parse_error(UnknownKey, end_of("\"type\": \"cube\"}"), Some("objects[1]"), &["radius", "cube"]),
        json("JSON: string for an integer", edit(BASE_JSON, "\"width\": 16", "\"width\": \"16\""))
            .parse_error(BadValue, end_of("\"16\""), Some("film.width"), &["string", "expected an integer"]),
        json("JSON: string for a number or vector", edit(BASE_JSON, "\"size\": 1}", "\"size\": \"big\"}"))
            .parse_error(BadValue, end_of("\"big\""), Some("objects[1].size"), &["string", "number"]),
        json("JSON: string in a vector",
             edit(BASE_JSON, "\"position\": [0, 1, 5]", "\"position\": [0, \"1\", 5]"))
            .parse_error(BadValue, end_of("\"1\""), Some("camera.position[1]"), &["string", "number"]),
        json("JSON: vector of four numbers",
             edit(BASE_JSON, "\"position\": [0, 1, 5]", "\"position\": [0, 1, 5, 6]"))
            .parse_error(BadValue, end_of("[0, 1, 5, 6]"), Some("camera.position"), &["length 4", "3"]),
        json("JSON: string deep in a triangle's vertices", with_triangle_json("[0, \"y\", 0]"))
            .parse_error(BadValue, end_of("\"y\""), Some("objects[2].vertices[2][1]"), &["string", "number"]),
        json("JSON: unknown sampler",
             edit(BASE_JSON, "  \"lights\"", "  \"render\": {\"sampler\": \"random\"},\n  \"lights\""))
            .parse_error(BadValue, end_of("\"random\""), Some("render.sampler"), &["random", "jittered"]),
        // serde_json gives a custom error on a number the position past the delimiter it
        // peeked at after the number (here the space after `1e39,`): only the line is checked.
        json("JSON: number beyond f32 in a vector",
             edit(BASE_JSON, "\"position\": [0, 1, 5]", "\"position\": [0, 1e39, 5]"))
            .parse_error(BadValue, line_only("1e39"), Some("camera.position[1]"), &["out of range"]),
        // JSON has no infinity; a number too large for a double is its way of writing one.
        // serde_json rejects it while reading the number: a syntax error, at the number.
        json("JSON: number beyond f64", edit(BASE_JSON, "\"fov\": 45", "\"fov\": 1e999"))
            .parse_error(Syntax, end_of("1e999"), Some("camera.fov"), &["number out of range"]),
        json("JSON: missing film.width", edit(BASE_JSON, "\"width\": 16, ", ""))
            .parse_error(MissingKey, end_of("{\"height\": 12}"), Some("film"), &["missing", "width"]),
        json("JSON: missing camera.position", edit(BASE_JSON, "\"position\": [0, 1, 5], ", ""))
            .parse_error(MissingKey, end_of("\"fov\": 45}"), Some("camera"), &["missing", "position"]),
        json("JSON: missing center of a cube", edit(BASE_JSON, "\"center\": [0, 0, 0], ", ""))
            .parse_error(MissingKey, end_of("\"size\": 1}"), Some("objects[1]"), &["missing", "center"]),
        json("JSON: unknown material", edit(BASE_JSON, "\"material\": \"red\"", "\"material\": \"rde\""))
            .build_error(UnknownName, at("\"material\""), Some("objects[1].material"),
                         &["unknown material", "\"rde\"", "known: red"]),
        json("JSON: unknown texture",
             edit(BASE_JSON, "\"specular\": 0.3}", "\"specular\": 0.3, \"texture\": \"wood\"}"))
            .build_error(UnknownName, at("\"texture\""), Some("materials.red.texture"),
                         &["unknown texture", "\"wood\""]),
        json("JSON: fov out of range", edit(BASE_JSON, "\"fov\": 45", "\"fov\": 180"))
            .build_error(BadValue, at("\"fov\""), Some("camera.fov"), &["fov", "not 180"]),
        json("JSON: degenerate camera", edit(BASE_JSON, "\"look_at\": [0, 0, 0]", "\"look_at\": [0, 1, 5]"))
            .build_error(BadValue, at("\"look_at\""), Some("camera.look_at"), &["degenerate"]),
        json("JSON: negative size", edit(BASE_JSON, "\"size\": 1}", "\"size\": -1}"))
            .build_error(BadValue, at("\"size\""), Some("objects[1].size"), &["negative"]),
        // serde_json stops at the closing quote of an unknown key: counted in characters, that
        // quote; counted in bytes, one column further.
        json("JSON: column after a non-ASCII key", "{\"film\": {\"width\": 16, \"höhe\": 12}}\n")
            .parse_error(UnknownKey, end_of("\"höhe\""), Some("film.höhe"), &["höhe"]),

        // --- JSON syntax ---
        // Inside a value, serde_json's path names the enclosing key.
        json("JSON: trailing comma", edit(BASE_JSON, "\"fov\": 45}", "\"fov\": 45,}"))
            .parse_error(Syntax, end_of("45,}"), Some("camera"), &["trailing comma"]),
        json("JSON: missing colon", edit(BASE_JSON, "\"width\": 16", "\"width\" 16"))
            .parse_error(Syntax, at("16,"), Some("film"), &["expected `:`"]),
        // Cut off after a newline: the line after the last, and the column is still 1-based.
        json("JSON: cut off", before(BASE_JSON, "  \"lights\""))
            .parse_error(Syntax, FileEnd, None, &["eof"]),
        json("JSON: text after the object", format!("{BASE_JSON}oops\n"))
            .parse_error(Syntax, at("oops"), None, &["trailing characters"]),
        json("JSON: empty file", "")
            .parse_error(Syntax, FileStart, None, &["eof"]),

        // --- JSON duplicates: valid JSON syntax, so bad values (TOML's are syntax errors) ---
        json("JSON: duplicate key", edit(BASE_JSON, "\"height\": 12}", "\"height\": 12, \"width\": 3}"))
            .parse_error(BadValue, end_of("12, \"width\""), Some("film"), &["duplicate", "width"]),
        json("JSON: duplicate key of an object", edit(BASE_JSON, "\"size\": 1}", "\"size\": 1, \"size\": 2}"))
            .parse_error(BadValue, end_of("\"size\": 2"), Some("objects[1].size"), &["duplicate", "size"]),
        json("JSON: duplicate material name",
             edit(BASE_JSON, "\"specular\": 0.3}}", "\"specular\": 0.3}, \"red\": {}}"))
            .parse_error(BadValue, end_of("}, \"red\""), Some("materials"), &["duplicate", "red"]),
    ];

    // fov must be strictly between 0 and 180 degrees.
    for fov in ["0", "180", "-10", "200"] {
        let line = format!("fov = {fov}");
        rows.push(
            toml(&format!("fov {fov}"), edit(BASE, "fov = 45", &line))
                .build_error(BadValue, at(&line), Some("camera.fov"),
                             &["fov must be between 0 and 180", fov]),
        );
    }
    rows
}

// ---------------------------------------------------------------------------------------------
// Scenes the table breaks
// ---------------------------------------------------------------------------------------------

/// The cube of BASE (objects[1]), all of its keys.
const CUBE: &str = "type = \"cube\"\nmaterial = \"red\"\ncenter = [0, 0, 0]\nsize = 1\n";

/// The cube of BASE_JSON.
const CUBE_JSON: &str =
    "{\"type\": \"cube\", \"material\": \"red\", \"center\": [0, 0, 0], \"size\": 1}";

/// The point light of BASE (lights[0]), all of its keys.
const POINT_LIGHT: &str = "type = \"point\"\nposition = [0, 5, 5]\n";

/// An area light's keys, but for `samples`.
const AREA_LIGHT: &str = "type = \"area\"\ncenter = [0, 5, 5]\nu = [1, 0, 0]\nv = [0, 0, 1]\n";

/// The material `red` of BASE, with its header.
const RED: &str = "[materials.red]\ndiffuse = [0.8, 0.1, 0.1]\nspecular = 0.3\n";

/// The keys of a valid camera.
const SIDE_CAMERA: &str = "position = [5, 1, 0]\nlook_at = [0, 0, 0]\nfov = 45\n";

/// The keys of a camera looking straight down: degenerate with the default up (+y).
const TOP_CAMERA: &str = "position = [0, 5, 0]\nlook_at = [0, 0, 0]\nfov = 30\n";

/// The first bytes of a PNG file: its signature and the start of its header chunk.
const PNG_START: &[u8] = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x10\0\0\0\x10\x08\x02\0\0\0";

/// A triangle with corners 1, 2, 3, for OBJ files.
const TRIANGLE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

/// `text` up to (not including) the first `needle`.
fn before<'a>(text: &'a str, needle: &str) -> &'a str {
    &text[..text.find(needle).expect("needle in the text")]
}

/// BASE with a `[render]` table holding `lines`.
fn with_render(lines: &str) -> String {
    format!("{BASE}\n[render]\n{lines}\n")
}

/// BASE with its `[camera]` called `front`.
/// A `[cameras.NAME]` table's body: fov 40 and one key at each of `frames`, in the order given.
fn keys(frames: &[i64]) -> String {
    let mut out = "fov = 40\n".to_owned();
    for (i, f) in frames.iter().enumerate() {
        out += &format!(
            "[[cameras.fly.keys]]\nframe = {f}\nposition = [{i}, 1, 5]\nlook_at = [0, 0, 0]\n"
        );
    }
    out
}

fn named_camera(text: &str) -> String {
    edit(text, "[camera]", "[cameras.front]")
}

/// BASE without its `[camera]` table.
fn without_camera(text: &str) -> String {
    format!(
        "{}{}",
        before(text, "[camera]"),
        &text[text.find("[materials").unwrap()..]
    )
}

/// `text` with the material `red` using the texture `name`.
fn with_material_texture(text: &str, name: &str) -> String {
    edit(
        text,
        "specular = 0.3\n",
        &format!("specular = 0.3\ntexture = \"{name}\"\n"),
    )
}

/// BASE with an image texture `t` that has `option` besides its file.
fn with_image_option(option: &str) -> String {
    format!("{BASE}\n[textures.t]\ntype = \"image\"\nfile = \"t.png\"\n{option}\n")
}

/// BASE with a triangle as objects[2], its third corner `third`.
fn with_triangle(third: &str) -> String {
    format!(
        "{BASE}\n[[objects]]\ntype = \"triangle\"\nvertices = [[0, 0, 0], [1, 0, 0], {third}]\n"
    )
}

/// BASE_JSON with a triangle as objects[2], its third corner `third`.
fn with_triangle_json(third: &str) -> String {
    edit(
        BASE_JSON,
        "\"size\": 1}\n",
        &format!(
            "\"size\": 1}},\n    {{\"type\": \"triangle\", \"vertices\": [[0, 0, 0], [1, 0, 0], {third}]}}\n"
        ),
    )
}

// ---------------------------------------------------------------------------------------------
// Rows and what they expect
// ---------------------------------------------------------------------------------------------

/// Which call rejects a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// `SceneFile::from_str`.
    Parse,
    /// `SceneFile::build`.
    Build,
}

/// Where an error must point, found in the scene text.
#[derive(Clone, Debug)]
enum At {
    /// The first character of the only occurrence of the needle, or of the `n`th (0-based).
    Start(String, Option<usize>),
    /// The last character of the only occurrence.
    End(String),
    /// The character just after the only occurrence.
    After(String),
    /// The first character of the value in the only occurrence of `key = value` (TOML) or
    /// `"key": value` (JSON).
    Value(String),
    /// The line of the only occurrence; the column is not checked (each use says why).
    Line(String),
    /// Line 1, column 1: errors about the whole file.
    FileStart,
    /// Just after the last character of the file.
    FileEnd,
}
use At::{FileEnd, FileStart};

fn at(needle: &str) -> At {
    At::Start(needle.to_owned(), None)
}
fn at_nth(needle: &str, n: usize) -> At {
    At::Start(needle.to_owned(), Some(n))
}
fn end_of(needle: &str) -> At {
    At::End(needle.to_owned())
}
fn after(needle: &str) -> At {
    At::After(needle.to_owned())
}
fn value_of(needle: &str) -> At {
    At::Value(needle.to_owned())
}
fn line_only(needle: &str) -> At {
    At::Line(needle.to_owned())
}

impl At {
    /// The expected line and column (`None`: not checked) in `text`.
    fn resolve(&self, text: &str) -> Result<(usize, Option<usize>), String> {
        let only = |needle: &str| -> Result<usize, String> {
            match text.matches(needle).count() {
                1 => Ok(text.find(needle).unwrap()),
                n => Err(format!("the needle {needle:?} occurs {n} times, not once")),
            }
        };
        let at_offset = |offset: usize| {
            let (line, column) = line_col(text, offset);
            (line, Some(column))
        };
        Ok(match self {
            At::Start(needle, None) => at_offset(only(needle)?),
            At::Start(needle, Some(n)) => {
                let (line, column) = nth_position_of(text, needle, *n);
                (line, Some(column))
            }
            At::End(needle) => {
                let last = needle.chars().last().map_or(0, char::len_utf8);
                at_offset(only(needle)? + needle.len() - last)
            }
            At::After(needle) => at_offset(only(needle)? + needle.len()),
            At::Value(needle) => {
                let sep = [" = ", ": "]
                    .iter()
                    .find_map(|s| needle.find(s).map(|i| i + s.len()))
                    .ok_or_else(|| format!("no ` = ` or `: ` in {needle:?}"))?;
                at_offset(only(needle)? + sep)
            }
            At::Line(needle) => (line_col(text, only(needle)?).0, None),
            At::FileStart => (1, Some(1)),
            At::FileEnd => at_offset(text.len()),
        })
    }
}

/// 1-based line and column, in characters, of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (
        before.matches('\n').count() + 1,
        before[line_start..].chars().count() + 1,
    )
}

/// What a row's error must be.
#[derive(Clone, Debug)]
struct Expect {
    stage: Stage,
    kind: ErrorKind,
    at: At,
    key: Option<&'static str>,
    words: Vec<&'static str>,
}

/// A bad scene and what its error must be.
struct Case {
    name: String,
    format: SceneFormat,
    text: String,
    /// Files written next to the scene: (path relative to it, contents).
    files: Vec<(&'static str, Vec<u8>)>,
    expect: Expect,
}

/// A row being written: the scene, before what its error must be.
struct Draft {
    name: String,
    format: SceneFormat,
    text: String,
    files: Vec<(&'static str, Vec<u8>)>,
}

fn toml(name: &str, text: impl Into<String>) -> Draft {
    draft(name, SceneFormat::Toml, text.into())
}

fn json(name: &str, text: impl Into<String>) -> Draft {
    draft(name, SceneFormat::Json, text.into())
}

fn draft(name: &str, format: SceneFormat, text: String) -> Draft {
    Draft {
        name: name.to_owned(),
        format,
        text,
        files: Vec::new(),
    }
}

impl Draft {
    /// Writes `contents` to `rel` next to the scene before it is built.
    fn file(mut self, rel: &'static str, contents: impl AsRef<[u8]>) -> Draft {
        self.files.push((rel, contents.as_ref().to_vec()));
        self
    }

    /// The scene must fail to parse with this error.
    fn parse_error(
        self,
        kind: ErrorKind,
        at: At,
        key: Option<&'static str>,
        words: &[&'static str],
    ) -> Case {
        self.expect(Stage::Parse, kind, at, key, words)
    }

    /// The scene must parse, then fail to build with this error.
    fn build_error(
        self,
        kind: ErrorKind,
        at: At,
        key: Option<&'static str>,
        words: &[&'static str],
    ) -> Case {
        self.expect(Stage::Build, kind, at, key, words)
    }

    fn expect(
        self,
        stage: Stage,
        kind: ErrorKind,
        at: At,
        key: Option<&'static str>,
        words: &[&'static str],
    ) -> Case {
        Case {
            name: self.name,
            format: self.format,
            text: self.text,
            files: self.files,
            expect: Expect {
                stage,
                kind,
                at,
                key,
                words: words.to_vec(),
            },
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Running and checking rows
// ---------------------------------------------------------------------------------------------

impl Case {
    /// The name the scene has in messages.
    fn file_name(&self) -> &'static str {
        match self.format {
            SceneFormat::Toml => "scene.toml",
            SceneFormat::Json => "scene.json",
        }
    }

    /// Parses and builds the scene with its files in `dir`.
    fn run(&self, dir: &Path) -> Outcome {
        for (rel, contents) in &self.files {
            let path = dir.join(rel);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, contents).unwrap();
        }
        match SceneFile::from_str(&self.text, self.format, self.file_name(), dir) {
            Err(e) => Some((Stage::Parse, e)),
            Ok(file) => file.build(1).err().map(|e| (Stage::Build, e)),
        }
    }
}

/// What a scene gave: the stage that rejected it and its error, or `None` when accepted.
type Outcome = Option<(Stage, SceneError)>;

/// An expectation with its position found in the text.
#[derive(Clone, Debug)]
struct Want {
    stage: Stage,
    kind: ErrorKind,
    line: usize,
    column: Option<usize>,
    key: Option<String>,
    words: Vec<&'static str>,
}

impl Case {
    fn want(&self) -> Result<Want, String> {
        let e = &self.expect;
        let (line, column) = e.at.resolve(&self.text)?;
        Ok(Want {
            stage: e.stage,
            kind: e.kind,
            line,
            column,
            key: e.key.map(str::to_owned),
            words: e.words.clone(),
        })
    }
}

/// How an error differs from what is wanted; empty when it is what is wanted.
fn mismatches(file_name: &str, want: &Want, got: &Outcome) -> Vec<String> {
    let Some((stage, error)) = got else {
        return vec!["the scene was accepted".to_owned()];
    };
    let mut out = Vec::new();
    if *stage != want.stage {
        out.push(format!("stage {stage:?}, want {:?}", want.stage));
    }
    if error.kind() != want.kind {
        out.push(format!("kind {:?}, want {:?}", error.kind(), want.kind));
    }
    let SceneError::Invalid {
        location, message, ..
    } = error
    else {
        out.push("not located in the file".to_owned());
        return out;
    };
    if location.line != Some(want.line) {
        out.push(format!("line {:?}, want {}", location.line, want.line));
    }
    match (location.column, want.column) {
        (None, _) => out.push("no column".to_owned()),
        (Some(got), Some(want)) if got != want => out.push(format!("column {got}, want {want}")),
        _ => {}
    }
    if location.key != want.key {
        out.push(format!("key {:?}, want {:?}", location.key, want.key));
    }
    let lower = message.to_lowercase();
    for word in &want.words {
        if !lower.contains(&word.to_lowercase()) {
            out.push(format!("{word:?} missing from the message"));
        }
    }
    // What every message must be: in the user's words (no Rust type names), and not repeating
    // the position the location already gives.
    for rust in ["i64", "u64", "f64", " at line "] {
        if message.contains(rust) {
            out.push(format!("the message says {rust:?}"));
        }
    }
    if message.trim().len() < 4 {
        out.push("the message says nothing".to_owned());
    }
    // The one line the command line prints: FILE:LINE:COL: KEY: message.
    let key = location
        .key
        .as_ref()
        .map_or(String::new(), |k| format!(": {k}"));
    let line = location.line.unwrap_or(0);
    let column = location.column.unwrap_or(0);
    let display = format!("{file_name}:{line}:{column}{key}: {message}");
    if error.to_string() != display {
        out.push(format!("displayed as {error:?}, want {display:?}"));
    }
    out
}

/// A row that ran.
struct Ran {
    case: Case,
    want: Want,
    got: Outcome,
}

/// Runs every row, each with a folder of its own for its files.
fn run_table(dir: &TempDir) -> Vec<Ran> {
    table()
        .into_iter()
        .enumerate()
        .map(|(i, case)| {
            let row_dir = dir.join(format!("row-{i}"));
            std::fs::create_dir_all(&row_dir).unwrap();
            let want = case
                .want()
                .unwrap_or_else(|e| panic!("row {:?} is wrong: {e}", case.name));
            let got = case.run(&row_dir);
            Ran { case, want, got }
        })
        .collect()
}

/// How a row is shown in a failure.
fn describe(case: &Case, got: &Outcome) -> String {
    let got = got
        .as_ref()
        .map_or("accepted".to_owned(), |(s, e)| format!("{s:?}: {e}"));
    format!("{:?} ({:?}): got {got}", case.name, case.format)
}

// ---------------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------------

#[test]
fn every_bad_scene_is_reported_where_it_is_wrong() {
    let dir = TempDir::new("errors-table");
    let rows = run_table(&dir);
    let failures: Vec<String> = rows
        .iter()
        .filter_map(|Ran { case, want, got }| {
            let m = mismatches(case.file_name(), want, got);
            (!m.is_empty()).then(|| format!("{}\n    {}", describe(case, got), m.join("\n    ")))
        })
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} rows fail:\n{}",
        failures.len(),
        rows.len(),
        failures.join("\n")
    );
}

#[test]
fn every_row_can_fail() {
    // Each expectation of each row, changed, must be reported: no row passes vacuously.
    let dir = TempDir::new("errors-vacuous");
    let mut vacuous = Vec::new();
    for Ran { case, want, got } in run_table(&dir) {
        let mut changed: Vec<(&str, Want)> = Vec::new();
        let mut w = want.clone();
        w.stage = match want.stage {
            Stage::Parse => Stage::Build,
            Stage::Build => Stage::Parse,
        };
        changed.push(("stage", w));
        let mut w = want.clone();
        w.kind = if want.kind == BadValue {
            Syntax
        } else {
            BadValue
        };
        changed.push(("kind", w));
        let mut w = want.clone();
        w.line += 1;
        changed.push(("line", w));
        if let Some(column) = want.column {
            let mut w = want.clone();
            w.column = Some(column + 1);
            changed.push(("column", w));
        }
        let mut w = want.clone();
        w.key = match &want.key {
            Some(_) => None,
            None => Some("film".to_owned()),
        };
        changed.push(("key", w));
        let mut w = want.clone();
        w.words.push("no such word");
        changed.push(("words", w));
        for (what, w) in changed {
            if mismatches(case.file_name(), &w, &got).is_empty() {
                vacuous.push(format!("{:?}: a wrong {what} passes", case.name));
            }
        }
    }
    assert!(vacuous.is_empty(), "{}", vacuous.join("\n"));
}

#[test]
fn the_table_covers_every_kind_in_both_formats() {
    let rows = table();
    let has = |format: SceneFormat, kind: ErrorKind| {
        rows.iter()
            .any(|c| c.format == format && c.expect.kind == kind)
    };
    for kind in [
        Syntax,
        UnknownKey,
        MissingKey,
        BadValue,
        UnknownName,
        MESH,
        IMAGE,
    ] {
        assert!(has(SceneFormat::Toml, kind), "no TOML row of kind {kind:?}");
    }
    for kind in [Syntax, UnknownKey, MissingKey, BadValue, UnknownName] {
        assert!(has(SceneFormat::Json, kind), "no JSON row of kind {kind:?}");
    }
    let mut names: Vec<&str> = rows.iter().map(|c| c.name.as_str()).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), rows.len(), "row names are unique");
}

#[test]
fn the_scenes_the_table_breaks_are_valid() {
    // Each row breaks one thing in these; as they are, they build.
    let dir = TempDir::new("errors-valid");
    dir.png("textures/wood.png", 2, 2, |x, y| {
        [(x * 200) as u8, (y * 200) as u8, 0]
    });
    dir.write("m.obj", format!("mtllib m.mtl\nusemtl m\n{TRIANGLE_OBJ}"));
    dir.write("m.mtl", "newmtl m\nmap_Kd textures/wood.png\n");
    for (name, format, text) in [
        ("base", SceneFormat::Toml, BASE.to_owned()),
        ("base", SceneFormat::Json, BASE_JSON.to_owned()),
        (
            "texture",
            SceneFormat::Toml,
            with_texture("textures/wood.png"),
        ),
        ("mesh", SceneFormat::Toml, with_mesh("m.obj")),
        ("named camera", SceneFormat::Toml, named_camera(BASE)),
        ("triangle", SceneFormat::Toml, with_triangle("[0, 1, 0]")),
        (
            "triangle",
            SceneFormat::Json,
            with_triangle_json("[0, 1, 0]"),
        ),
        ("render", SceneFormat::Toml, with_render("samples = 4")),
        (
            "image option",
            SceneFormat::Toml,
            with_image_option("wrap = \"clamp\"")
                .replace("file = \"t.png\"", "file = \"textures/wood.png\""),
        ),
    ] {
        SceneFile::from_str(&text, format, "scene", dir.path())
            .and_then(|f| f.build(1))
            .unwrap_or_else(|e| panic!("{name} ({format:?}): {e}"));
    }
}

#[test]
fn unreadable_scene_files_are_file_errors() {
    let dir = TempDir::new("errors-file");
    let missing = dir.join("nosuch.toml");
    let e = SceneFile::load(&missing).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::File, "{e}");
    assert!(e.location().is_none(), "{e}");
    assert!(
        e.to_string().contains(&missing.display().to_string()),
        "{e}"
    );

    let yaml = dir.write("scene.yaml", BASE);
    let e = SceneFile::load(&yaml).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::File, "{e}");
    assert!(e.location().is_none(), "{e}");
    let message = e.to_string();
    assert!(
        message.contains(".toml") && message.contains(".json"),
        "{message}"
    );
}

#[test]
fn a_byte_that_is_not_utf8_is_located() {
    let dir = TempDir::new("errors-utf8");
    // Latin-1 "é" (0xE9) in a material's name: line 12, column 16.
    let text = edit(
        BASE,
        "[materials.red]",
        "[materials.red]\n[materials.\"caf\u{1}\"]",
    );
    let mut bytes = text.into_bytes();
    let at = bytes.iter().position(|&b| b == 1).unwrap();
    bytes[at] = 0xE9;
    let path = dir.write("latin1.toml", &bytes);
    let e = SceneFile::load(&path).unwrap_err();
    let location = e.location().unwrap_or_else(|| panic!("not located: {e}"));
    assert_eq!(
        (location.line, location.column),
        (Some(12), Some(16)),
        "{e}"
    );
    let message = e.to_string();
    assert!(
        message.contains("0xE9") && message.contains("UTF-8"),
        "{message}"
    );
}
