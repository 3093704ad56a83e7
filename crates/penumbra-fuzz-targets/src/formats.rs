//! The promises of the file formats' readers beyond "no panic": a glTF error at a JSON path
//! (a line and column only for JSON that is not JSON), PLY ASCII rows read as lines, and a
//! decoded Radiance (or any) environment map sampled without overflow.

use glam::Vec2;
use penumbra::{decode_texture_image, inspect_ply_bytes, EnvironmentMap, ObjInfo};

/// A glTF reader's error: JSON that deserializes nowhere is named by its JSON path; only a
/// syntax error (no value to name yet) gives a line and column.
pub(crate) fn check_gltf_message(message: &str) {
    assert!(
        !message.chars().any(char::is_control),
        "a control character in the message {message:?}"
    );
    if message.contains(" column ") {
        assert!(
            message.contains("cannot be read"),
            "a glTF error gives a line and column instead of its JSON path: {message}"
        );
    }
}

/// The rows of each element of an ASCII PLY header that has properties (those take lines),
/// summed; `None` for a binary file or a header that does not parse here.
fn ascii_rows(header: &str) -> Option<u64> {
    let mut lines = header.lines().map(str::trim);
    if !lines.any(|l| l == "format ascii 1.0") {
        return None;
    }
    let (mut rows, mut count, mut properties) = (0u64, 0u64, false);
    for line in header.lines().map(str::trim) {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["element", _, n] => {
                rows += if properties { count } else { 0 };
                (count, properties) = (n.parse().ok()?, false);
            }
            ["property", ..] => properties = true,
            _ => {}
        }
    }
    Some(rows + if properties { count } else { 0 })
}

/// A PLY file that reads: when it is ASCII with one row a line (as many lines as rows, and no
/// values dropped at their ends), a value added at the end of every line of its body (what
/// VCGlib writes after each face) changes nothing but a warning.
pub(crate) fn check_ply_rows(data: &[u8], info: &ObjInfo) {
    if info.warnings.iter().any(|w| w.contains("ends of")) {
        return;
    }
    let (triangles, vertices) = (info.triangles, info.vertices);
    // The header ends where the reader ends it: at the first line whose only word is
    // `end_header` (spaces and tabs around it allowed).
    let mut start = 0;
    let Some(end) = data.split_inclusive(|&b| b == b'\n').find_map(|line| {
        start += line.len();
        let words = std::str::from_utf8(line).ok()?.split_whitespace();
        words.eq(["end_header"]).then_some(start)
    }) else {
        return;
    };
    let (Ok(header), Ok(body)) = (
        std::str::from_utf8(&data[..end]),
        std::str::from_utf8(&data[end..]),
    ) else {
        return;
    };
    let Some(rows) = ascii_rows(header) else {
        return;
    };
    let lines: Vec<&str> = body.lines().filter(|l| !l.trim().is_empty()).collect();
    if lines.len() as u64 != rows || body.contains('\r') {
        return;
    }
    let padded: String = lines.iter().map(|l| format!("{l} 7\n")).collect();
    let padded = format!("{header}{padded}");
    let again = inspect_ply_bytes(padded.as_bytes())
        .unwrap_or_else(|e| panic!("a value at the end of each row broke the file: {e}"));
    assert_eq!((again.triangles, again.vertices), (triangles, vertices));
    assert!(
        again.warnings.iter().any(|w| w.contains("ends of")),
        "the dropped values are not warned of: {:?}",
        again.warnings
    );
}

/// An environment map file (Radiance HDR, OpenEXR, PNG or JPEG, by its content), decoded with
/// a bound on its memory; one that decodes to 2 × 2 texels or more makes a map whose samples
/// have finite radiance and a finite positive density, and a finite mean and peak.
pub fn hdr(data: &[u8]) {
    const MAX_BYTES: u64 = 64 << 20;
    let Ok(image) = decode_texture_image(data, true, Some(MAX_BYTES)) else {
        return;
    };
    assert_eq!(
        image.texels.len(),
        image.width as usize * image.height as usize
    );
    let Ok(map) = EnvironmentMap::new(image.width, image.height, image.texels) else {
        return;
    };
    let (mean, peak) = map.mean_and_peak();
    assert!(mean.is_finite() && peak.is_finite(), "{mean} {peak}");
    for a in 0..4 {
        for b in 0..4 {
            let u = Vec2::new((a as f32 + 0.5) / 4.0, (b as f32 + 0.5) / 4.0);
            let s = map.sample(u);
            assert!(s.radiance.is_finite(), "radiance {} at {u}", s.radiance);
            assert!(s.pdf.is_finite() && s.pdf > 0.0, "density {} at {u}", s.pdf);
            assert!(s.direction.is_finite());
        }
    }
}
