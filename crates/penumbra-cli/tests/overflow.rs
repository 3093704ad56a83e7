//! Radiance beyond f32 that no bound at the scene's keys can catch (issue 10, class 2): the
//! physical model's inverse-square falloff right next to a bright light. A float image is
//! refused (exit 2, no file) rather than written with infinite pixels; an 8-bit image clamps.

#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use std::process::{Command, Stdio};

use support::TempDir;

#[test]
fn infinite_radiance_is_refused_in_a_float_image_and_clamped_in_png() {
    let sb = TempDir::new("cli-overflow");
    // The one pixel's ray meets the wall at the origin, 1e-6 from a light of the largest
    // emission: 1e32 / (1e-6)² overflows.
    let scene = sb.write(
        "s.toml",
        r#"[film]
width = 1
height = 1

[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
fov = 45

[render]
light_model = "physical"
sampler = "center"

[[lights]]
type = "point"
position = [0, 0, 1e-6]
intensity = 1e32

[[objects]]
type = "quad"
corner = [-1, -1, 0]
u = [2, 0, 0]
v = [0, 2, 0]
"#,
    );
    for (ext, code) in [("exr", 2), ("pfm", 2), ("png", 0)] {
        let out = sb.join(format!("out.{ext}"));
        let run = Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .env_remove("RUST_BACKTRACE")
            .arg("render")
            .arg(&scene)
            .arg("-o")
            .arg(&out)
            .arg("--quiet")
            .stdin(Stdio::null())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(code), "{ext}: {stderr}");
        if code == 2 {
            assert!(
                stderr.starts_with("error: ") && stderr.lines().count() == 1,
                "{ext}: {stderr}"
            );
            assert!(stderr.contains("beyond the range"), "{ext}: {stderr}");
            assert!(!out.exists(), "{ext}: an image was written");
        } else {
            assert!(out.exists(), "{ext}: no image");
        }
    }
}
