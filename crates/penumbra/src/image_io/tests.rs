//! Writing films: cancelled writes, PFM rows, non-finite values, refusals, bytes.

use super::encode::Prepared;
use super::*;

#[test]
fn a_cancelled_write_leaves_the_old_file_and_no_temporary_file() {
    let dir = std::env::temp_dir().join(format!("penumbra-cancel-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let film = Film {
        width: 2,
        height: 1,
        pixels: vec![glam::Vec3::ONE; 2],
        alpha: None,
    };
    for ext in ["png", "jpg", "exr", "pfm"] {
        let path = dir.join(format!("out.{ext}"));
        std::fs::write(&path, b"old").unwrap();
        let got = write_image_unless(&film, &path, None, &AtomicBool::new(true));
        assert!(matches!(got, Err(ImageError::Cancelled)), "{ext}: {got:?}");
        assert_eq!(std::fs::read(&path).unwrap(), b"old", "{ext}");
        write_image_unless(&film, &path, None, &AtomicBool::new(false)).unwrap();
        assert_ne!(std::fs::read(&path).unwrap(), b"old", "{ext}");
    }
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 4, "temporary files left: {names:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn pfm_rows_go_bottom_up_across_several_writes() {
    // 3,600 bytes a row: 292 rows a write, so 700 rows take three writes, the last short.
    let (width, height) = (300u32, 700u32);
    let pixels: Vec<glam::Vec3> = (0..width * height)
        .map(|i| glam::Vec3::new(i as f32, -(i as f32), 0.5 + i as f32))
        .collect();
    let film = Film {
        width,
        height,
        pixels,
        alpha: None,
    };
    let mut w = BufWriter::with_capacity(WRITE_BUFFER, Cursor::new(Vec::new()));
    encode(&film, &Prepared::Floats, OutputFormat::Pfm, &mut w).unwrap();
    let bytes = w.into_inner().unwrap().into_inner();
    let header = format!("PF\n{width} {height}\n-1.0\n");
    assert_eq!(&bytes[..header.len()], header.as_bytes());
    let floats: Vec<f32> = bytes[header.len()..]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect();
    let want: Vec<f32> = film
        .pixels
        .chunks(width as usize)
        .rev()
        .flatten()
        .flat_map(|p| p.to_array())
        .collect();
    assert!(
        floats == want,
        "the file's floats are not the film's rows bottom up"
    );
}

#[test]
fn float_formats_never_store_a_non_finite_value() {
    let dir = std::env::temp_dir().join(format!("penumbra-nonfinite-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for bad in [f32::INFINITY, f32::NEG_INFINITY, f32::NAN] {
        let film = Film {
            width: 3,
            height: 2,
            pixels: (0..6)
                .map(|i| glam::Vec3::splat(if i == 4 { bad } else { 0.5 }))
                .collect(),
            alpha: None,
        };
        for ext in ["exr", "pfm"] {
            let path = dir.join(format!("out.{ext}"));
            let got = write_image(&film, &path, None);
            let Err(ImageError::NonFinite { x: 1, y: 1, .. }) = got else {
                panic!("{ext} {bad}: {got:?}");
            };
            assert!(!path.exists(), "{ext} {bad}: a file was written");
        }
        // 8-bit formats clamp (NaN to 0), as SPEC §7 says.
        write_image(&film, &dir.join("out.png"), None).unwrap();
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// What cannot be encoded is refused before anything is converted or written: a gamma
/// that is not one, a JPEG wider or higher than 65535 pixels, an encoding beyond the
/// memory available.
#[test]
fn unencodable_images_are_refused_up_front() {
    let dir = std::env::temp_dir().join(format!("penumbra-refused-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let film = |width: u32, height: u32| Film {
        width,
        height,
        pixels: vec![glam::Vec3::splat(0.5); (width * height) as usize],
        alpha: None,
    };
    let small = film(2, 2);
    let bad_gammas = [
        0.0,
        -0.0,
        -2.2,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        1e-40,
    ];
    for g in bad_gammas {
        for name in ["g.png", "g.jpg"] {
            let got = write_image(&small, &dir.join(name), Some(g));
            assert!(matches!(got, Err(ImageError::BadGamma(_))), "{g}: {got:?}");
            assert!(!dir.join(name).exists(), "{g}: {name} written");
        }
        let got = encode_image(&small, OutputFormat::Png, Some(g));
        assert!(matches!(got, Err(ImageError::BadGamma(_))), "{g}: {got:?}");
    }
    for (width, height) in [(65_536, 1), (1, 65_536)] {
        let wide = film(width, height);
        let got = write_image(&wide, &dir.join("w.jpg"), None).unwrap_err();
        assert!(matches!(got, ImageError::TooLarge { .. }), "{got:?}");
        assert!(got.to_string().contains("65535"), "{got}");
        assert!(!dir.join("w.jpg").exists());
        let got = encode_image(&wide, OutputFormat::Jpeg, None).unwrap_err();
        assert!(matches!(got, ImageError::TooLarge { .. }), "{got:?}");
    }
    write_image(&film(65_535, 1), &dir.join("w.jpg"), Some(2.2)).unwrap();
    // 1000 × 1000 pixels as a PNG need about 7 MB beyond the film.
    let big = film(1000, 1000);
    let path = Path::new("big.png");
    let cases = [
        (OutputFormat::Png, false, Some(1 << 20), false),
        (OutputFormat::Png, false, Some(100 << 20), true),
        (OutputFormat::Png, false, None, true),
        (OutputFormat::Exr, false, Some(10 << 20), false),
        (OutputFormat::Pfm, false, Some(0), true),
        (OutputFormat::Pfm, true, Some(10 << 20), false),
    ];
    for (format, in_memory, available, fits) in cases {
        let got = check_encodable(&big, format, None, path, in_memory, available);
        assert_eq!(
            got.is_ok(),
            fits,
            "{format:?} {in_memory} {available:?}: {got:?}"
        );
        if let Err(e) = got {
            let text = e.to_string();
            assert!(
                text.contains("1000x1000") && text.contains("memory"),
                "{text}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn encoded_bytes_are_the_bytes_written() {
    let film = Film {
        width: 3,
        height: 2,
        pixels: (0..6)
            .map(|i| crate::math::Rgb::new(i as f32 / 5.0, 0.5, 2.0))
            .collect(),
        alpha: None,
    };
    let dir = std::env::temp_dir().join(format!("penumbra-encode-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, format) in [
        ("a.png", OutputFormat::Png),
        ("a.pfm", OutputFormat::Pfm),
        ("a.exr", OutputFormat::Exr),
        ("a.jpg", OutputFormat::Jpeg),
    ] {
        let path = dir.join(name);
        write_image(&film, &path, None).unwrap();
        let written = std::fs::read(&path).unwrap();
        assert_eq!(
            encode_image(&film, format, None).unwrap(),
            written,
            "{name}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
