//! `--poses` (issue 28): the intrinsics K and poses written for each image put a world point
//! on the pixel the renderer shows it at, and `--poses-format nerf` writes a transforms.json.

mod harness;
#[path = "../../penumbra/tests/support/mod.rs"]
mod support;

use harness::{ok, read_pfm, run_in};
use serde_json::Value;
use support::{TempDir, BASE_CAMERA as STILL, BASE_TOML};

/// The base scene seen by a keyframed camera `fly` (frames 0 to 4) looking off-centre with a
/// tilted up, so that no axis or centre is special.
fn scene() -> String {
    BASE_TOML.replace(
        STILL,
        "[cameras.fly]\nup = [0.2, 1, 0.1]\n\
         [[cameras.fly.keys]]\nframe = 0\nposition = [1.5, 2, 4]\nlook_at = [0.3, 0.1, -0.4]\nfov = 50\n\
         [[cameras.fly.keys]]\nframe = 4\nposition = [-2, 1.5, 3.5]\nlook_at = [0.2, 0, 0]\nfov = 38\n",
    )
}

fn read_json(path: &std::path::Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

fn matrix(v: &Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|row| {
            row.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

/// The largest distance, over every pixel with a hit, between the pixel's integer
/// coordinates and where K and world_to_camera put the world point its position AOV shows.
fn largest_reprojection_error(dir: &TempDir, pose: &Value, position: &str) -> f64 {
    let (w, h, channels, values) = read_pfm(&dir.join(position));
    assert_eq!(channels, 3);
    assert_eq!(pose["width"].as_u64(), Some(w as u64));
    assert_eq!(pose["height"].as_u64(), Some(h as u64));
    let (k, m) = (matrix(&pose["K"]), matrix(&pose["world_to_camera"]));
    let (mut worst, mut hits) = (0.0f64, 0);
    for j in 0..h {
        for i in 0..w {
            let p: Vec<f64> = values[(j * w + i) * 3..][..3]
                .iter()
                .map(|&x| x as f64)
                .collect();
            if p.iter().all(|&x| x == 0.0) {
                continue; // a miss
            }
            hits += 1;
            let c: Vec<f64> = (0..3)
                .map(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3])
                .collect();
            assert!(c[2] > 0.0, "pixel {i},{j} is behind the camera");
            let u = k[0][0] * c[0] / c[2] + k[0][1] * c[1] / c[2] + k[0][2];
            let v = k[1][1] * c[1] / c[2] + k[1][2];
            worst = worst.max((u - i as f64).hypot(v - j as f64));
        }
    }
    assert!(hits > w * h / 4, "only {hits} pixels hit");
    worst
}

#[test]
fn k_and_the_pose_put_each_hit_on_the_pixel_that_shows_it() {
    let dir = TempDir::new("poses-reproject");
    dir.write("s.toml", scene());
    ok(run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "--camera",
            "fly",
            "--frames",
            "0:4:2",
            "--width",
            "40",
            "--height",
            "30",
            "--aov",
            "position",
            "-o",
            "out/f{frame}.png",
            "--poses",
            "out/poses.json",
        ],
    ));
    let poses = read_json(&dir.join("out/poses.json"));
    let frames = poses["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 3);
    for (pose, frame) in frames.iter().zip([0, 2, 4]) {
        assert_eq!(pose["frame"], frame);
        assert_eq!(pose["camera"], "fly");
        assert_eq!(pose["file"], format!("out/f{frame}.png"));
        // A centred camera: cx = (W − 1)/2, cy = (H − 1)/2.
        let k = matrix(&pose["K"]);
        assert_eq!((k[0][2], k[1][2]), (19.5, 14.5));
        let worst = largest_reprojection_error(&dir, pose, &format!("out/f{frame}.position.pfm"));
        // Half a pixel is the bound; the convention is right to a hair.
        assert!(worst < 0.01, "frame {frame}: {worst} pixels off");
    }
    // OpenGL's pose is OpenCV's with y and z flipped; world_to_camera is its inverse.
    let p = &frames[1];
    let (cv, gl) = (
        matrix(&p["camera_to_world"]),
        matrix(&p["camera_to_world_opengl"]),
    );
    for r in 0..3 {
        assert_eq!(
            (gl[r][0], gl[r][1], gl[r][2], gl[r][3]),
            (cv[r][0], -cv[r][1], -cv[r][2], cv[r][3])
        );
    }
}

#[test]
fn a_regions_k_is_shifted_to_the_regions_pixels() {
    let dir = TempDir::new("poses-region");
    dir.write("s.toml", scene());
    ok(run_in(
        dir.path(),
        [
            "render",
            "s.toml",
            "--camera",
            "fly",
            "--frames",
            "3",
            "--width",
            "40",
            "--height",
            "30",
            "--pixelbounds",
            "12,34,4,27",
            "--aov",
            "position",
            "-o",
            "r.png",
            "--poses",
            "p.json",
        ],
    ));
    let poses = read_json(&dir.join("p.json"));
    let pose = &poses["frames"][0];
    let k = matrix(&pose["K"]);
    assert_eq!((k[0][2], k[1][2]), (19.5 - 12.0, 14.5 - 4.0));
    let worst = largest_reprojection_error(&dir, pose, "r.position.pfm");
    assert!(worst < 0.01, "{worst} pixels off");
}

#[test]
fn nerf_transforms_name_the_images_beside_them_with_opengl_poses() {
    let dir = TempDir::new("poses-nerf");
    dir.write("s.toml", scene());
    let args = [
        "render", "s.toml", "--camera", "fly", "--width", "16", "--height", "12",
    ];
    ok(run_in(
        dir.path(),
        args.iter().copied().chain([
            "-o",
            "data/images/{frame:03}.png",
            "--poses",
            "data/transforms.json",
            "--poses-format",
            "nerf",
        ]),
    ));
    ok(run_in(
        dir.path(),
        args.iter()
            .copied()
            .chain(["-o", "cv/{frame}.png", "--poses", "cv/poses.json"]),
    ));
    let nerf = read_json(&dir.join("data/transforms.json"));
    let cv = read_json(&dir.join("cv/poses.json"));
    assert_eq!(nerf["camera_model"], "OPENCV");
    // NeRF counts pixel centres at +½: a centred camera has cx = W/2.
    assert_eq!(
        (nerf["w"].as_u64(), nerf["h"].as_u64()),
        (Some(16), Some(12))
    );
    assert_eq!(
        (nerf["cx"].as_f64(), nerf["cy"].as_f64()),
        (Some(8.0), Some(6.0))
    );
    let fy = nerf["fl_y"].as_f64().unwrap();
    let angle_y = nerf["camera_angle_y"].as_f64().unwrap();
    assert!((angle_y - 50f64.to_radians()).abs() < 1e-6, "{angle_y}");
    assert!((fy - 6.0 / (25f64.to_radians()).tan()).abs() < 1e-9, "{fy}");
    let frames = nerf["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 5);
    for (f, (frame, pose)) in frames
        .iter()
        .zip(cv["frames"].as_array().unwrap())
        .enumerate()
    {
        let file = frame["file_path"].as_str().unwrap();
        assert_eq!(file, format!("images/{f:03}.png"));
        assert!(dir.join("data").join(file).is_file(), "{file}");
        assert_eq!(frame["transform_matrix"], pose["camera_to_world_opengl"]);
    }
}

#[test]
fn a_calibrated_camera_writes_its_k_and_nerf_refuses_a_skew_it_cannot_hold() {
    let dir = TempDir::new("poses-k");
    // K in pixels of the file's 16×12 film; rendered at twice the size, it scales.
    let camera = |skew: f64| {
        format!(
            "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\n\
             K = [[20, {skew:?}, 7], [0, 18, 5.5], [0, 0, 1]]\n"
        )
    };
    dir.write("k.toml", BASE_TOML.replace(STILL, &camera(0.0)));
    dir.write("skew.toml", BASE_TOML.replace(STILL, &camera(0.5)));
    let args = ["--width", "32", "--height", "24", "--poses"];
    ok(run_in(
        dir.path(),
        [&["render", "k.toml", "-o", "k.png"][..], &args, &["k.json"]].concat(),
    ));
    let k = matrix(&read_json(&dir.join("k.json"))["frames"][0]["K"]);
    assert_eq!(k, [[40.0, 0.0, 14.5], [0.0, 36.0, 11.5], [0.0, 0.0, 1.0]]);
    let nerf = [
        &["render", "skew.toml", "-o", "skew.png"][..],
        &args,
        &["n.json", "--poses-format", "nerf"],
    ];
    let line = harness::error_line(&run_in(dir.path(), nerf.concat()), 2);
    assert!(line.contains("skew") && line.contains("NeRF"), "{line}");
    assert!(!dir.join("n.json").exists() && !dir.join("skew.png").exists());
}

/// The rotation (rows) of a unit quaternion (w, x, y, z), as COLMAP's `QuaternionToRotationMatrix`.
fn rotation([w, x, y, z]: [f64; 4]) -> [[f64; 3]; 3] {
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

#[test]
fn colmap_models_hold_each_images_k_and_world_to_camera_pose() {
    let dir = TempDir::new("poses-colmap");
    dir.write("s.toml", scene());
    let args = [
        "render", "s.toml", "--camera", "fly", "--width", "16", "--height", "12",
    ];
    let run = |extra: &[&str]| ok(run_in(dir.path(), [&args[..], extra].concat()));
    run(&[
        "-o",
        "out/images/{frame:03}.png",
        "--poses",
        "out/sparse/0",
        "--poses-format",
        "colmap",
    ]);
    run(&["-o", "cv/{frame}.png", "--poses", "cv/poses.json"]);
    let cv = read_json(&dir.join("cv/poses.json"));
    let text = |name: &str| std::fs::read_to_string(dir.join("out/sparse/0").join(name)).unwrap();
    let data = |t: String| -> Vec<Vec<String>> {
        t.lines()
            .filter(|l| !l.starts_with('#') && !l.is_empty())
            .map(|l| l.split(' ').map(str::to_owned).collect())
            .collect()
    };
    let cameras = data(text("cameras.txt"));
    let images = data(text("images.txt"));
    assert!(text("points3D.txt").lines().all(|l| l.starts_with('#')));
    // The path's fov changes from frame to frame: a camera each.
    assert_eq!((cameras.len(), images.len()), (5, 5));
    let num = |s: &String| s.parse::<f64>().unwrap();
    for (i, image) in images.iter().enumerate() {
        let frame = &cv["frames"][i];
        assert_eq!(image[9], format!("{i:03}.png"));
        let camera = cameras.iter().find(|c| c[0] == image[8]).unwrap();
        let k = matrix(&frame["K"]);
        assert_eq!(&camera[1..4], ["PINHOLE", "16", "12"]);
        let params: Vec<f64> = camera[4..].iter().map(num).collect();
        // COLMAP's pixel centres lie at +½ (serde_json reads a float to within an ulp).
        let expected = [k[0][0], k[1][1], k[0][2] + 0.5, k[1][2] + 0.5];
        for (p, e) in params.iter().zip(expected) {
            assert!(
                (p - e).abs() <= 1e-12 * e.abs(),
                "{params:?} vs {expected:?}"
            );
        }
        let q = [1, 2, 3, 4].map(|j| num(&image[j]));
        assert!(q[0] >= 0.0);
        let (r, t) = (rotation(q), [5, 6, 7].map(|j| num(&image[j])));
        let w2c = matrix(&frame["world_to_camera"]);
        for a in 0..3 {
            assert!((t[a] - w2c[a][3]).abs() < 1e-12, "{t:?} vs {w2c:?}");
            for b in 0..3 {
                // The pose is the camera's f32 frame: orthonormal to about 1e-7.
                assert!((r[a][b] - w2c[a][b]).abs() < 1e-6, "{r:?} vs {w2c:?}");
            }
        }
    }
    // A .json name is not a folder.
    let line = harness::error_line(
        &run_in(
            dir.path(),
            [
                &args[..],
                &[
                    "-o",
                    "x{frame}.png",
                    "--poses",
                    "p.json",
                    "--poses-format",
                    "colmap",
                ],
            ]
            .concat(),
        ),
        2,
    );
    assert!(line.contains("a folder"), "{line}");
}

#[test]
fn lens_models_are_written_as_each_format_names_them() {
    let dir = TempDir::new("poses-lens");
    let lens =
        |keys: &str| format!("[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\n{keys}\n");
    let k = "K = [[20, 0, 7.5], [0, 18, 5.5], [0, 0, 1]]";
    let scenes = [
        ("radial", format!("model = \"opencv\"\n{k}\ndistortion = [-0.2, 0.05, 0.001, -0.002, 0.0]")),
        ("rational", format!("model = \"opencv\"\n{k}\ndistortion = [-0.2, 0.05, 0.001, -0.002, 0.01, 0.02, 0, 0]")),
        ("prism", format!("model = \"opencv\"\n{k}\ndistortion = [-0.2, 0.05, 0.001, -0.002, 0, 0, 0, 0, 0.001, 0, 0, 0]")),
        ("fish", format!("model = \"fisheye\"\n{k}\ndistortion = [0.01, -0.002, 0.0003, 0]\nmax_angle = 100")),
        ("pano", "model = \"equirectangular\"".to_owned()),
    ];
    for (name, keys) in &scenes {
        let file = format!("{name}.toml");
        dir.write(&file, BASE_TOML.replace(STILL, &lens(keys)));
    }
    let run = |name: &str, format: &str, to: &str| {
        run_in(
            dir.path(),
            [
                "render",
                &format!("{name}.toml"),
                "-o",
                &format!("{name}-{format}.png"),
                "--poses",
                to,
                "--poses-format",
                format,
            ],
        )
    };
    // penumbra's layout carries the model and its coefficients as given.
    ok(run("fish", "penumbra", "fish.json"));
    let frame = &read_json(&dir.join("fish.json"))["frames"][0];
    assert_eq!(frame["model"], "fisheye");
    assert_eq!(
        frame["distortion"],
        serde_json::json!([0.01, -0.002, 0.0003, 0.0])
    );
    assert_eq!(frame["max_angle"], 100.0);
    // So does the record beside an image.
    ok(run_in(
        dir.path(),
        ["render", "fish.toml", "-o", "meta.png", "--meta"],
    ));
    let record = read_json(&dir.join("meta.meta.json"));
    assert_eq!(record["model"], "fisheye");
    assert_eq!(record["distortion"], frame["distortion"]);
    // COLMAP: the model that holds the coefficients, after fx fy cx cy.
    let colmap_camera = |name: &str| {
        ok(run(name, "colmap", &format!("{name}-sparse")));
        let text = std::fs::read_to_string(dir.join(format!("{name}-sparse/cameras.txt"))).unwrap();
        let line = text
            .lines()
            .find(|l| !l.starts_with('#'))
            .unwrap()
            .to_owned();
        line.split(' ')
            .skip(1)
            .map(str::to_owned)
            .collect::<Vec<_>>()
    };
    let radial = colmap_camera("radial");
    assert_eq!(radial[0], "OPENCV");
    assert_eq!(radial[7..], ["-0.2", "0.05", "0.001", "-0.002"]);
    let rational = colmap_camera("rational");
    assert_eq!((rational[0].as_str(), rational.len()), ("FULL_OPENCV", 15));
    let fish = colmap_camera("fish");
    assert_eq!(fish[0], "OPENCV_FISHEYE");
    assert_eq!(fish[3..7], ["20.0", "18.0", "8.0", "6.0"]);
    for (name, words) in [("prism", "thin-prism"), ("pano", "panorama")] {
        let line = harness::error_line(&run(name, "colmap", "x"), 2);
        assert!(line.contains(words) && line.contains("COLMAP"), "{line}");
    }
    // nerfstudio: its camera_model names, k3 among the radial terms.
    for (name, model) in [
        ("radial", "OPENCV"),
        ("fish", "OPENCV_FISHEYE"),
        ("pano", "EQUIRECTANGULAR"),
    ] {
        ok(run(name, "nerf", &format!("{name}-nerf.json")));
        let t = read_json(&dir.join(format!("{name}-nerf.json")));
        assert_eq!(t["camera_model"], model, "{name}");
    }
    let t = read_json(&dir.join("radial-nerf.json"));
    assert_eq!(
        (t["k1"].as_f64(), t["k3"].as_f64(), t["p2"].as_f64()),
        (Some(-0.2), Some(0.0), Some(-0.002))
    );
    let pano = read_json(&dir.join("pano-nerf.json"));
    assert_eq!(
        (pano["fl_x"].as_f64(), pano["w"].as_f64()),
        (Some(8.0), Some(16.0))
    );
    let line = harness::error_line(&run("rational", "nerf", "r.json"), 2);
    assert!(
        line.contains("rational") && line.contains("nerfstudio"),
        "{line}"
    );
}

#[test]
fn a_moving_camera_writes_its_lens_at_every_frame() {
    let dir = TempDir::new("poses-moving-lens");
    let camera =
        "[cameras.turn]\nmodel = \"fisheye\"\nK = [[20, 0, 7.5], [0, 18, 5.5], [0, 0, 1]]\n\
                  distortion = [0.01, -0.002, 0.0003, 0]\nmax_angle = 100\n\
                  path = { type = \"orbit\", center = [0, 0, 0], radius = 5, frames = 3 }\n";
    dir.write("turn.toml", BASE_TOML.replace(STILL, camera));
    let args = [
        "render",
        "turn.toml",
        "-q",
        "--frames",
        "all",
        "-o",
        "f{frame}.png",
    ];
    ok(run_in(
        dir.path(),
        [&args[..], &["--poses", "p.json"]].concat(),
    ));
    let frames = read_json(&dir.join("p.json"))["frames"].clone();
    let frames = frames.as_array().unwrap();
    assert_eq!(frames.len(), 3);
    for f in frames {
        assert_eq!(f["model"], "fisheye", "{f}");
        assert_eq!(matrix(&f["K"])[0], [20.0, 0.0, 7.5], "{f}");
    }
    ok(run_in(
        dir.path(),
        [&args[..], &["--poses", "t.json", "--poses-format", "nerf"]].concat(),
    ));
    let t = read_json(&dir.join("t.json"));
    assert_eq!(t["camera_model"], "OPENCV_FISHEYE");
    assert_eq!(
        (t["fl_x"].as_f64(), t["k1"].as_f64()),
        (Some(20.0), Some(0.01))
    );
}
