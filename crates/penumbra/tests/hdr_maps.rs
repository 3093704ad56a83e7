//! Environment map files decoded by their content: Radiance HDR (flat scanlines too) and
//! OpenEXR linear, PNG through the sRGB curve whatever the extension; the largest RGBE texels
//! sampled without overflow; the decoder's memory limit that of the documented texel limit.

mod support;

use penumbra::{decode_texture_image, render, Film, RenderOptions, Scene, SceneFile};
use support::TempDir;

/// A camera looking at the sky (+z) under the environment `light`, 4 × 4 pixels.
fn sky(dir: &TempDir, light: &str) -> Result<Scene, penumbra::SceneError> {
    let text = format!(
        "[film]\nwidth = 4\nheight = 4\n[camera]\nposition = [0, 0, 0]\nlook_at = [0, 0, 1]\n\
         up = [0, 1, 0]\nfov = 10\n[render]\nsampler = \"center\"\n[[lights]]\n\
         type = \"environment\"\n{light}\n"
    );
    SceneFile::load(dir.write("scene.toml", text))?.build(0)
}

fn film(scene: &Scene) -> Film {
    render(&scene.world, &scene.settings, &RenderOptions::default())
        .expect("render")
        .0
}

/// A Radiance file of `width × height` whose texels (RGBE) are written flat.
fn radiance(width: u32, height: u32, texel: impl Fn(u32, u32) -> [u8; 4]) -> Vec<u8> {
    let mut bytes =
        format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n").into_bytes();
    for y in 0..height {
        for x in 0..width {
            bytes.extend(texel(x, y));
        }
    }
    bytes
}

#[test]
fn the_largest_rgbe_texels_at_a_tiny_intensity_render_finite() {
    let dir = TempDir::new("hdr-largest");
    dir.write("max.hdr", radiance(16, 8, |_, _| [255; 4]));
    let scene = sky(&dir, "file = \"max.hdr\"\nintensity = 1e-30\nsamples = 2").unwrap();
    let film = film(&scene);
    // 255 · 2^119 · 1e-30 everywhere.
    let want = 255.0 * 2f64.powi(119) * 1e-30;
    for p in &film.pixels {
        assert!(p.is_finite(), "{p}");
        assert!((f64::from(p.x) / want - 1.0).abs() < 1e-5, "{p} vs {want}");
    }
}

#[test]
fn the_content_picks_the_curve_not_the_extension() {
    let dir = TempDir::new("hdr-content");
    dir.png("sky.png", 4, 2, |_, _| [128, 128, 128]);
    std::fs::copy(dir.join("sky.png"), dir.join("sky.hdr")).unwrap();
    let png = film(&sky(&dir, "file = \"sky.png\"").unwrap());
    let named_hdr = film(&sky(&dir, "file = \"sky.hdr\"").unwrap());
    let srgb = ((128.0f32 / 255.0 + 0.055) / 1.055).powf(2.4);
    assert!((png.pixels[5].x - srgb).abs() < 1e-4, "{}", png.pixels[5]);
    assert_eq!(png.pixels, named_hdr.pixels);
    // A Radiance file named .png is linear: 0.5 stays 0.5.
    dir.write("flat.png", radiance(4, 2, |_, _| [128, 128, 128, 128]));
    let linear = film(&sky(&dir, "file = \"flat.png\"").unwrap());
    assert!(
        (linear.pixels[5].x - 0.5).abs() < 1e-6,
        "{}",
        linear.pixels[5]
    );
}

#[test]
fn a_flat_4_by_2_radiance_file_is_read() {
    // Radiance writes widths under 8 flat; its first texel (2, 2, 100, e) looks like the
    // start of a run-length encoded scanline to a reader that does not check the width.
    let dir = TempDir::new("hdr-flat");
    let bytes = radiance(4, 2, |x, y| match (x, y) {
        (0, 0) => [2, 2, 100, 129],
        _ => [128, 128, 128, 129],
    });
    dir.write("small.hdr", &bytes);
    let image = decode_texture_image(&bytes, true, None).unwrap();
    assert_eq!((image.width, image.height), (4, 2));
    assert_eq!(
        image.texels[0].to_array(),
        [2.0 / 128.0, 2.0 / 128.0, 100.0 / 128.0]
    );
    assert_eq!(image.texels[7].to_array(), [1.0; 3]);
    let film = film(&sky(&dir, "file = \"small.hdr\"").unwrap());
    assert!(film.pixels.iter().all(|p| p.is_finite() && p.x > 0.0));
}

#[test]
fn the_decoder_memory_limit_is_the_texel_limit() {
    // 10240 × 5120 (52 million texels, under 2^26): the header alone. The decoder takes it
    // (its default limit of 512 MiB refused it up front) and stops at the missing scanlines.
    let header = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 5120 +X 10240\n";
    let e = decode_texture_image(header, true, None).unwrap_err();
    assert!(!e.to_lowercase().contains("limit"), "{e}");
    // Over the texel limit: refused by name before anything is decoded.
    let header = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 8193 +X 8192\n";
    let e = decode_texture_image(header, true, None).unwrap_err();
    assert!(
        e.contains("8192x8193") && e.contains("67108864 texels"),
        "{e}"
    );
    // The message of a scene names the file and the limit.
    let dir = TempDir::new("hdr-limit");
    dir.write("huge.hdr", header);
    let e = sky(&dir, "file = \"huge.hdr\"").unwrap_err().to_string();
    assert!(
        e.contains("huge.hdr") && e.contains("67108864 texels"),
        "{e}"
    );
}
