//! The lens models of a still camera (`model = "opencv" | "fisheye" | "equirectangular" |
//! "orthographic"`) and depth of field. Every hit a pixel's centre ray finds projects back,
//! through the model's forward formula written out here (OpenCV's `projectPoints` and
//! `fisheye.projectPoints`, the documented panorama and orthographic maps), onto that pixel's
//! centre within 1e-3 px; what a model cannot see is a miss; an aperture of 0 is the pinhole
//! byte for byte, and a surface on the plane in focus stays sharp; bad keys are refused at
//! their keys.

use glam::{DMat3, DVec2, DVec3};
use penumbra::{
    encode_8bit, render, render_with_aovs, RenderOptions, Scene, SceneFile, SceneFormat,
};

const W: u32 = 96;
const H: u32 = 64;

/// A room of quads and a sphere around the origin, seen by `camera` (a `[camera]` table's
/// keys) on a `W × H` film with the centre sampler.
fn scene(camera: &str) -> Result<Scene, penumbra::SceneError> {
    let text = format!(
        "[film]\nwidth = {W}\nheight = {H}\n[camera]\n{camera}\n[render]\nsampler = \"center\"\n\
         [[lights]]\ntype = \"point\"\nposition = [0, 2, 2]\n\
         [[objects]]\ntype = \"quad\"\ncorner = [-4, -2, -3]\nu = [8, 0, 0]\nv = [0, 5, 0]\n\
         [[objects]]\ntype = \"quad\"\ncorner = [-4, -2, 4]\nu = [8, 0, 0]\nv = [0, 0, -7]\n\
         [[objects]]\ntype = \"quad\"\ncorner = [-4, 3, -3]\nu = [8, 0, 0]\nv = [0, 0, 9]\n\
         [[objects]]\ntype = \"sphere\"\ncenter = [0.7, -0.5, 0]\nradius = 0.8\n"
    );
    SceneFile::from_str(&text, SceneFormat::Toml, "lens.toml", ".")?.build(1)
}

/// The camera's pose: at (0.5, 0.3, 2.5), turned 20° about y and 10° about x from looking
/// down −z; camera to world in OpenCV's axes.
fn pose() -> (DMat3, DVec3) {
    let (a, b) = (20f64.to_radians(), 10f64.to_radians());
    let flip = DMat3::from_cols(DVec3::X, -DVec3::Y, -DVec3::Z);
    let r = DMat3::from_rotation_y(a) * DMat3::from_rotation_x(b) * flip;
    (r, DVec3::new(0.5, 0.3, 2.5))
}

/// `camera_to_world = ...` of [`pose`].
fn pose_key() -> String {
    let (r, t) = pose();
    let row = |i: usize| {
        let c = r.row(i);
        format!("[{:?}, {:?}, {:?}, {:?}]", c.x, c.y, c.z, t[i])
    };
    format!(
        "camera_to_world = [{}, {}, {}, [0, 0, 0, 1]]",
        row(0),
        row(1),
        row(2)
    )
}

/// K of the tests: fx ≠ fy, an off-centre principal point, no skew (which OpenCV's
/// `projectPoints` does not read).
const K: [[f64; 3]; 3] = [[42.0, 0.0, 49.3], [0.0, 40.5, 30.9], [0.0, 0.0, 1.0]];

/// A fisheye's K: the film's corners lie 168° off the axis, its sides' centres 141°.
const FISHEYE_K: [[f64; 3]; 3] = [[20.0, 0.0, 49.3], [0.0, 19.5, 30.9], [0.0, 0.0, 1.0]];

fn k_key(k: [[f64; 3]; 3]) -> String {
    let row = |r: [f64; 3]| format!("[{:?}, {:?}, {:?}]", r[0], r[1], r[2]);
    format!("K = [{}, {}, {}]", row(k[0]), row(k[1]), row(k[2]))
}

/// `cv2.projectPoints`' distortion of normalized point `p`, with 12 coefficients.
fn opencv_distort(d: &[f64; 12], p: DVec2) -> DVec2 {
    let [k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4] = *d;
    let (x, y) = (p.x, p.y);
    let r2 = x * x + y * y;
    let radial = (1.0 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2)
        / (1.0 + k4 * r2 + k5 * r2 * r2 + k6 * r2 * r2 * r2);
    DVec2::new(
        x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) + s1 * r2 + s2 * r2 * r2,
        y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y + s3 * r2 + s4 * r2 * r2,
    )
}

/// `cv2.fisheye.projectPoints`' distortion of the camera-space point `c`, by its angle off
/// the axis (atan2, which also covers points beside and behind the camera).
fn fisheye_distort(k: &[f64; 4], c: DVec3) -> DVec2 {
    let r = c.truncate().length();
    let theta = r.atan2(c.z);
    let t2 = theta * theta;
    let theta_d = theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
    c.truncate() * (theta_d / r)
}

/// Pixel coordinates (centres at integers) of a normalized point through `k`.
fn through_k(k: [[f64; 3]; 3], p: DVec2) -> DVec2 {
    DVec2::new(k[0][0] * p.x + k[0][2], k[1][1] * p.y + k[1][2])
}

/// Renders `camera` with the AOVs and checks that every hit projects by `project` (of the
/// hit in camera space, OpenCV axes) onto its pixel's centre; returns the number of hits.
fn reprojects(camera: &str, project: impl Fn(DVec3) -> DVec2) -> usize {
    let s = scene(camera).unwrap_or_else(|e| panic!("{camera}: {e}"));
    let (_, aovs, _) = render_with_aovs(&s.world, &s.settings, &RenderOptions::default()).unwrap();
    let (r, t) = pose();
    let mut hits = 0;
    let mut worst = (0f64, 0, 0);
    for y in 0..aovs.height {
        for x in 0..aovs.width {
            let a = aovs.get(x, y);
            if !a.depth.is_finite() {
                continue;
            }
            hits += 1;
            let c = r.transpose() * (a.position.as_dvec3() - t);
            let e = project(c) - DVec2::new(f64::from(x), f64::from(y));
            if e.abs().max_element() > worst.0 {
                worst = (e.abs().max_element(), x, y);
            }
        }
    }
    assert!(
        worst.0 < 1e-3,
        "{camera}: pixel {},{}'s hit projects {} px from its centre",
        worst.1,
        worst.2,
        worst.0
    );
    hits
}

#[test]
fn a_pinhole_of_k_with_skew_reprojects_exactly() {
    // K as OpenCV's camera matrix: u = fx·x + skew·y + cx.
    let k = [[70.0, 0.8, 51.3], [0.0, 64.5, 33.9], [0.0, 0.0, 1.0]];
    let row = |r: [f64; 3]| format!("[{:?}, {:?}, {:?}]", r[0], r[1], r[2]);
    let camera = format!(
        "K = [{}, {}, {}]\n{}",
        row(k[0]),
        row(k[1]),
        row(k[2]),
        pose_key()
    );
    let hits = reprojects(&camera, |c| {
        let (x, y) = (c.x / c.z, c.y / c.z);
        DVec2::new(k[0][0] * x + k[0][1] * y + k[0][2], k[1][1] * y + k[1][2])
    });
    assert!(hits as u32 > W * H / 4, "{hits} hits");
}

#[test]
fn opencv_lenses_reproject_exactly_with_4_5_8_and_12_coefficients() {
    let sets: [&[f64]; 4] = [
        &[-0.28, 0.07, 0.0002, -0.0001],
        &[-0.28, 0.07, 0.0002, -0.0001, 0.01],
        &[0.1, -0.05, 0.001, 0.002, 0.01, 0.05, -0.02, 0.003],
        &[
            -0.2, 0.05, 0.001, -0.002, 0.0, 0.02, 0.01, 0.0, 0.002, -0.001, 0.001, 0.0005,
        ],
    ];
    for set in sets {
        let mut d = [0.0; 12];
        d[..set.len()].copy_from_slice(set);
        let list = set.iter().map(|v| format!("{v:?}")).collect::<Vec<_>>();
        let camera = format!(
            "model = \"opencv\"\n{}\ndistortion = [{}]\n{}",
            k_key(K),
            list.join(", "),
            pose_key()
        );
        let hits = reprojects(&camera, |c| {
            through_k(K, opencv_distort(&d, DVec2::new(c.x / c.z, c.y / c.z)))
        });
        assert!(hits as u32 > W * H / 2, "{camera}: {hits} hits");
    }
}

#[test]
fn fisheye_lenses_reproject_exactly_and_see_nothing_beyond_max_angle() {
    let k = [0.02, -0.01, 0.003, -0.0005];
    let list = k.map(|v| format!("{v:?}")).join(", ");
    let mut counts = vec![];
    for max_angle in [60.0, 90.0, 120.0] {
        let camera = format!(
            "model = \"fisheye\"\n{}\ndistortion = [{list}]\nmax_angle = {max_angle:?}\n{}",
            k_key(FISHEYE_K),
            pose_key()
        );
        let hits = reprojects(&camera, |c| {
            let angle = c.truncate().length().atan2(c.z).to_degrees();
            assert!(angle <= max_angle + 1e-6, "a hit {angle}° off the axis");
            through_k(FISHEYE_K, fisheye_distort(&k, c))
        });
        counts.push(hits);
    }
    // The film reaches 168° off the axis: a wider view sees more of the room.
    assert!(counts[0] < counts[1] && counts[1] < counts[2], "{counts:?}");
}

#[test]
fn panoramas_follow_the_documented_map() {
    let camera = format!("model = \"equirectangular\"\n{}", pose_key());
    let hits = reprojects(&camera, |c| {
        let longitude = c.x.atan2(c.z);
        let latitude = (-c.y / c.length()).asin();
        let tau = std::f64::consts::TAU;
        DVec2::new(
            f64::from(W) * (longitude / tau + 0.5) - 0.5,
            f64::from(H) * (0.5 - latitude / (0.5 * tau)) - 0.5,
        )
    });
    // Inside the room, all but the open side is seen.
    assert!(hits as u32 > W * H / 2, "{hits}");
}

#[test]
fn orthographic_rays_are_parallel_and_span_height() {
    let height = 3.5;
    let camera = format!(
        "model = \"orthographic\"\nheight = {height}\n{}",
        pose_key()
    );
    let hits = reprojects(&camera, |c| {
        let half = 0.5 * height;
        let aspect = f64::from(W) / f64::from(H);
        DVec2::new(
            (c.x / (half * aspect) + 1.0) * 0.5 * f64::from(W) - 0.5,
            (c.y / half + 1.0) * 0.5 * f64::from(H) - 0.5,
        )
    });
    assert!(hits as u32 > W * H / 2, "{hits}");
}

/// PSNR in dB of `a` against `b`, over their 8-bit values.
fn psnr(a: &[u8], b: &[u8]) -> f64 {
    let mse = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2))
        .sum::<f64>()
        / a.len() as f64;
    10.0 * (255.0 * 255.0 / mse.max(1e-12)).log10()
}

fn bytes(s: &Scene) -> Vec<u8> {
    let (film, _) = render(&s.world, &s.settings, &RenderOptions::default()).unwrap();
    let values = film.pixels.iter().flat_map(|p| p.to_array());
    values.map(|c| encode_8bit(c, s.gamma)).collect()
}

#[test]
fn an_aperture_of_0_is_the_pinhole_and_the_focus_plane_stays_sharp() {
    let at = "position = [0, 0, 6]\nlook_at = [0, 0, 0]\nfov = 40";
    let pinhole = bytes(&scene(at).unwrap());
    let closed = scene(&format!("{at}\naperture_radius = 0\nfocus_distance = 6"));
    assert_eq!(bytes(&closed.unwrap()), pinhole);
    // The back wall (z = −3) is 9 in front of the camera, and nothing else is in view: in
    // focus there, a wide aperture leaves it as the pinhole sees it, and blurs it when
    // focused elsewhere.
    let at = "position = [-2.5, 0.5, 6]\nlook_at = [-2.5, 0.5, -3]\nfov = 20";
    let lens = |focus: f64| {
        let camera = format!("{at}\naperture_radius = 0.4\nfocus_distance = {focus:?}");
        bytes(&scene(&camera).unwrap())
    };
    let reference = bytes(&scene(at).unwrap());
    let (good, bad) = (psnr(&lens(9.0), &reference), psnr(&lens(3.0), &reference));
    assert!(good >= 50.0, "in focus: {good} dB");
    assert!(
        bad < good - 10.0,
        "out of focus {bad} dB vs in focus {good} dB"
    );
}

#[test]
fn bad_lens_keys_are_refused_at_their_keys() {
    let at = "position = [0, 0, 6]\nlook_at = [0, 0, 0]";
    let k = k_key(K);
    let cases = [
        (
            format!("model = \"opencv\"\n{k}\ndistortion = [0.1, 0.2, 0.3]\n{at}"),
            "camera.distortion",
            "4, 5, 8 or 12",
        ),
        (
            format!("model = \"opencv\"\n{k}\ndistortion = [0.1, 0.2, nan, 0]\n{at}"),
            "camera.distortion",
            "finite",
        ),
        (
            format!("model = \"opencv\"\n{k}\n{at}"),
            "camera",
            "distortion",
        ),
        (
            format!("model = \"fisheye\"\nfov = 90\ndistortion = [0, 0, 0, 0]\n{at}"),
            "camera",
            "takes K",
        ),
        (
            format!("model = \"fisheye\"\n{k}\ndistortion = [-0.5, 0, 0, 0]\nmax_angle = 60\n{at}"),
            "camera.max_angle",
            "stop growing",
        ),
        (
            format!("model = \"fisheye\"\n{k}\ndistortion = [0, 0, 0, 0]\nmax_angle = 200\n{at}"),
            "camera.max_angle",
            "between 0 and 180",
        ),
        (
            format!("model = \"equirectangular\"\nfov = 40\n{at}"),
            "camera",
            "no fov or K",
        ),
        (
            format!("model = \"orthographic\"\nheight = -1\n{at}"),
            "camera.height",
            "greater than 0",
        ),
        (format!("model = \"orthographic\"\n{at}"), "camera", "height"),
        (
            format!("model = \"orthographic\"\nheight = 2\naperture_radius = 0.1\nfocus_distance = 3\n{at}"),
            "camera",
            "no aperture",
        ),
        (
            format!("fov = 40\naperture_radius = 0.1\n{at}"),
            "camera",
            "focus_distance",
        ),
        (
            format!("fov = 40\naperture_radius = -0.1\nfocus_distance = 3\n{at}"),
            "camera.aperture_radius",
            "at least 0",
        ),
        (
            format!("fov = 40\nmax_angle = 100\n{at}"),
            "camera",
            "fisheye",
        ),
        (format!("model = \"lens\"\nfov = 40\n{at}"), "camera", "model"),
    ];
    for (camera, key, words) in cases {
        let Err(e) = scene(&camera) else {
            panic!("{camera}: accepted");
        };
        let e = e.to_string();
        assert!(e.contains(key) && e.contains(words), "{camera}: {e}");
    }
}
