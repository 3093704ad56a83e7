//! Rendered pixels against closed forms: small scenes built from TOML text through the public
//! API, rendered, and compared pixel by pixel with values computed here, in f64, straight from
//! the formulas of SPEC §3 (docs/spec.md) (camera), §4 (pixel sampling), §5 (intersection), §6 (shading) and
//! §7 (output). Nothing here calls the library's own math: the expected side re-derives every
//! ray, hit point, normal, light sample and texel from the SPEC text.
//!
//! Most scenes use `sampler = "center"` and a camera aimed so that we know which ray hits what
//! (a 1×1 film's only ray is the camera's forward direction, so it hits `look_at`).
//!
//! Tolerances (see the constants below):
//! - [`TOL`]: 1e-4 relative (floored at 0.01 in magnitude), for f32 rendering against f64
//!   expectations of plain arithmetic.
//! - [`TEX_TOL`]: 1e-3 absolute where textures and the sRGB curve are involved.
//! - [`SPHERE_TOL`]: 3e-3 absolute for the tessellated sphere against the true sphere.
//!
//! Pixels whose rays or shadow rays pass within a small margin of an edge are skipped (SPEC §5
//! leaves such ties to the implementation); every test asserts that it still checked enough
//! pixels.

use std::f64::consts::{FRAC_1_SQRT_2, PI};
use std::fmt::Display;
mod support;

use std::path::Path;

use glam::{DMat3, DVec2, DVec3, Vec3};
use penumbra::{
    render, write_image, Film, PixelBounds, RenderOptions, Scene, SceneFile, SceneFormat,
};
use support::TempDir;

/// Relative tolerance of plain f32 arithmetic against f64 (floored, see [`assert_close`]).
const TOL: f64 = 1e-4;
/// Absolute tolerance where texture decoding and the sRGB curve are involved.
const TEX_TOL: f64 = 1e-3;
/// Absolute tolerance of the tessellated sphere's shading against the true sphere's.
const SPHERE_TOL: f64 = 3e-3;

// ------------------------------------------------------------------------------------------
// Running scenes
// ------------------------------------------------------------------------------------------

fn build_in(text: &str, base_dir: &Path) -> Scene {
    SceneFile::from_str(text, SceneFormat::Toml, "test.toml", base_dir)
        .and_then(|f| f.build(0))
        .unwrap_or_else(|e| panic!("{e}\n--- scene ---\n{text}"))
}

fn render_with(scene: &Scene, options: &RenderOptions) -> Film {
    render(&scene.world, &scene.settings, options)
        .expect("render")
        .0
}

fn render_in(text: &str, base_dir: &Path) -> Film {
    render_with(&build_in(text, base_dir), &RenderOptions::default())
}

fn render_text(text: &str) -> Film {
    render_in(text, Path::new("."))
}

fn bits(film: &Film) -> Vec<[u32; 3]> {
    film.pixels
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

// ------------------------------------------------------------------------------------------
// Scene text
// ------------------------------------------------------------------------------------------

fn v3(v: DVec3) -> String {
    format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z)
}

fn rgb(r: f64, g: f64, b: f64) -> DVec3 {
    DVec3::new(r, g, b)
}

fn grey(c: f64) -> DVec3 {
    DVec3::splat(c)
}

/// The `[render]` table: the center sampler plus `extra` lines.
fn render_section(extra: &str) -> String {
    format!("[render]\nsampler = \"center\"\n{extra}\n\n")
}

/// Phong material coefficients (k_a, k_d, k_s, p) of SPEC §6.
#[derive(Clone, Copy, Debug)]
struct Mat {
    ka: DVec3,
    kd: DVec3,
    ks: DVec3,
    p: f64,
}

impl Mat {
    fn diffuse(ka: DVec3, kd: DVec3) -> Self {
        Mat {
            ka,
            kd,
            ks: DVec3::ZERO,
            p: 16.0,
        }
    }

    fn toml(&self, name: &str) -> String {
        format!(
            "[materials.{name}]\nambient = {}\ndiffuse = {}\nspecular = {}\nshininess = {:?}\n\n",
            v3(self.ka),
            v3(self.kd),
            v3(self.ks),
            self.p
        )
    }
}

/// A quad object; an empty `material` leaves the default material.
fn quad_toml(material: &str, corner: DVec3, u: DVec3, v: DVec3) -> String {
    let material = if material.is_empty() {
        String::new()
    } else {
        format!("material = \"{material}\"\n")
    };
    format!(
        "[[objects]]\ntype = \"quad\"\n{material}corner = {}\nu = {}\nv = {}\n\n",
        v3(corner),
        v3(u),
        v3(v)
    )
}

/// A 40×40 quad in the z = 0 plane centered on the origin, facing +z (u × v = +z).
fn floor_toml(material: &str) -> String {
    quad_toml(
        material,
        DVec3::new(-20.0, -20.0, 0.0),
        DVec3::new(40.0, 0.0, 0.0),
        DVec3::new(0.0, 40.0, 0.0),
    )
}

fn point_light_toml(position: DVec3, color: DVec3, intensity: f64) -> String {
    format!(
        "[[lights]]\ntype = \"point\"\nposition = {}\ncolor = {}\nintensity = {intensity:?}\n\n",
        v3(position),
        v3(color)
    )
}

/// An area light and the same light as the SPEC §6 formulas see it.
#[derive(Clone, Copy, Debug)]
struct AreaLight {
    center: DVec3,
    u: DVec3,
    v: DVec3,
    n: u32,
    color: DVec3,
    intensity: f64,
}

impl AreaLight {
    fn toml(&self) -> String {
        format!(
            "[[lights]]\ntype = \"area\"\ncenter = {}\nu = {}\nv = {}\nsamples = {}\ncolor = {}\n\
             intensity = {:?}\n\n",
            v3(self.center),
            v3(self.u),
            v3(self.v),
            self.n,
            v3(self.color),
            self.intensity
        )
    }

    /// SPEC §6: the cell centers center + ((k + ½)/N − ½)·u + ((l + ½)/N − ½)·v.
    fn samples(&self) -> Vec<DVec3> {
        let n = self.n as f64;
        let mut out = Vec::new();
        for k in 0..self.n {
            for l in 0..self.n {
                let a = (k as f64 + 0.5) / n - 0.5;
                let b = (l as f64 + 0.5) / n - 0.5;
                out.push(self.center + a * self.u + b * self.v);
            }
        }
        out
    }

    /// Seed model: every sample is a point light of color·intensity/N², both sides.
    fn seed_weight(&self) -> DVec3 {
        self.color * self.intensity / (self.n * self.n) as f64
    }

    /// Physical model: E_s = color·intensity·max(0, −n_l·l_s)·(|u × v|/N²)/d_s².
    fn physical_e(&self, x: DVec3, y: DVec3) -> DVec3 {
        let cross = self.u.cross(self.v);
        let n_l = cross.normalize();
        let l = (y - x).normalize();
        let d2 = (y - x).length_squared();
        self.color
            * self.intensity
            * (-n_l.dot(l)).max(0.0)
            * (cross.length() / (self.n * self.n) as f64)
            / d2
    }
}

// ------------------------------------------------------------------------------------------
// SPEC formulas in f64
// ------------------------------------------------------------------------------------------

/// A ray `o + t·d` with unit `d`.
#[derive(Clone, Copy, Debug)]
struct Ray {
    o: DVec3,
    d: DVec3,
}

/// The pinhole camera of SPEC §3 and the film it renders.
#[derive(Clone, Copy, Debug)]
struct Cam {
    eye: DVec3,
    look_at: DVec3,
    up: DVec3,
    fov: f64,
    width: u32,
    height: u32,
}

impl Cam {
    fn new(eye: DVec3, look_at: DVec3, fov: f64, width: u32, height: u32) -> Self {
        Cam {
            eye,
            look_at,
            up: DVec3::Y,
            fov,
            width,
            height,
        }
    }

    /// A 1×1 film: its one center sample looks exactly at `look_at`.
    fn probe(eye: DVec3, look_at: DVec3) -> Self {
        Cam::new(eye, look_at, 30.0, 1, 1)
    }

    /// The `[film]` and `[camera]` tables.
    fn toml(&self) -> String {
        format!(
            "[film]\nwidth = {}\nheight = {}\n\n[camera]\nposition = {}\nlook_at = {}\nup = {}\n\
             fov = {:?}\n\n",
            self.width,
            self.height,
            v3(self.eye),
            v3(self.look_at),
            v3(self.up),
            self.fov
        )
    }

    /// SPEC §3: f = normalize(c − e), r = normalize(f × w), u = r × f, h = tan(fov/2),
    /// a = width/height; direction normalize(f + (2x/W − 1)·a·h·r + (1 − 2y/H)·h·u).
    fn ray(&self, x: f64, y: f64) -> Ray {
        let f = (self.look_at - self.eye).normalize();
        let r = f.cross(self.up).normalize();
        let u = r.cross(f);
        let h = (self.fov.to_radians() / 2.0).tan();
        let a = self.width as f64 / self.height as f64;
        let (w, hh) = (self.width as f64, self.height as f64);
        let d = f + (2.0 * x / w - 1.0) * a * h * r + (1.0 - 2.0 * y / hh) * h * u;
        Ray {
            o: self.eye,
            d: d.normalize(),
        }
    }

    /// The ray through the center of pixel (i, j) (SPEC §4: (i + ½, j + ½)).
    fn pixel(&self, i: u32, j: u32) -> Ray {
        self.ray(i as f64 + 0.5, j as f64 + 0.5)
    }

    fn pixels(&self) -> impl Iterator<Item = (u32, u32)> {
        let (w, h) = (self.width, self.height);
        (0..h).flat_map(move |j| (0..w).map(move |i| (i, j)))
    }
}

/// Where the line `o + t·d` meets the parallelogram `corner + a·u + b·v` (any t, any a, b):
/// `(t, a, b)`, or `None` when the line is parallel to its plane.
fn parallelogram_coords(
    o: DVec3,
    d: DVec3,
    corner: DVec3,
    u: DVec3,
    v: DVec3,
) -> Option<(f64, f64, f64)> {
    let n = u.cross(v);
    let denom = n.dot(d);
    if denom.abs() < 1e-12 {
        return None;
    }
    let t = n.dot(corner - o) / denom;
    let p = o + t * d - corner;
    let a = p.cross(v).dot(n) / n.length_squared();
    let b = u.cross(p).dot(n) / n.length_squared();
    Some((t, a, b))
}

/// How a segment or ray relates to a parallelogram, with `margin` (in units of u and v) of
/// doubt around its edges.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Crossing {
    /// Crosses the inside, at parameter t and parallelogram coordinates (a, b).
    Inside(f64, f64, f64),
    /// Misses it clearly.
    Outside,
    /// Too close to an edge to say.
    Edge,
}

fn crossing(
    o: DVec3,
    d: DVec3,
    t_range: (f64, f64),
    corner: DVec3,
    u: DVec3,
    v: DVec3,
    margin: f64,
) -> Crossing {
    let Some((t, a, b)) = parallelogram_coords(o, d, corner, u, v) else {
        return Crossing::Outside;
    };
    if t <= t_range.0 || t >= t_range.1 {
        return Crossing::Outside;
    }
    let inside = |x: f64| x > margin && x < 1.0 - margin;
    let outside = |x: f64| x < -margin || x > 1.0 + margin;
    if inside(a) && inside(b) {
        Crossing::Inside(t, a, b)
    } else if outside(a) || outside(b) {
        Crossing::Outside
    } else {
        Crossing::Edge
    }
}

/// Whether the shadow segment from `x` to `y` crosses the parallelogram (None: too close to
/// its edge to say).
fn blocks(x: DVec3, y: DVec3, corner: DVec3, u: DVec3, v: DVec3) -> Option<bool> {
    match crossing(x, y - x, (1e-6, 1.0 - 1e-6), corner, u, v, 1e-3) {
        Crossing::Inside(..) => Some(true),
        Crossing::Outside => Some(false),
        Crossing::Edge => None,
    }
}

/// SPEC §6 with 0⁰ = 1.
fn pow0(base: f64, p: f64) -> f64 {
    if p == 0.0 {
        1.0
    } else {
        base.powf(p)
    }
}

/// The specular base of SPEC §6: r·v (Phong, r = 2(n·l)n − l) or n·h (Blinn-Phong,
/// h = normalize(l + v)), clamped at 0.
fn spec_base(n: DVec3, l: DVec3, v: DVec3, blinn: bool) -> f64 {
    let base = if blinn {
        n.dot((l + v).normalize())
    } else {
        (2.0 * n.dot(l) * n - l).dot(v)
    };
    base.max(0.0)
}

/// Seed model B_s = T·k_d·max(0, n·l) + k_s·max(0, r·v)^p, and 0 when n·l ≤ 0.
fn seed_brdf(n: DVec3, l: DVec3, v: DVec3, m: &Mat, t: DVec3, blinn: bool) -> DVec3 {
    let cos = n.dot(l);
    if cos <= 0.0 {
        return DVec3::ZERO;
    }
    t * m.kd * cos + m.ks * pow0(spec_base(n, l, v, blinn), m.p)
}

/// Physical model B_s = (T·k_d/π + k_s·(p + 2)/(2π)·max(0, r·v)^p)·max(0, n·l), with
/// (p + 8)/(8π) and n·h for Blinn-Phong.
fn physical_brdf(n: DVec3, l: DVec3, v: DVec3, m: &Mat, blinn: bool) -> DVec3 {
    let cos = n.dot(l);
    if cos <= 0.0 {
        return DVec3::ZERO;
    }
    let norm = if blinn {
        (m.p + 8.0) / (8.0 * PI)
    } else {
        (m.p + 2.0) / (2.0 * PI)
    };
    (m.kd / PI + m.ks * norm * pow0(spec_base(n, l, v, blinn), m.p)) * cos
}

/// The sRGB transfer curve's inverse (IEC 61966-2-1).
fn srgb_to_linear(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The sRGB transfer curve (IEC 61966-2-1).
fn linear_to_srgb(c: f64) -> f64 {
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Rotation about x by `deg` degrees, right-hand rule: (x, y cos − z sin, y sin + z cos).
fn rot_x(deg: f64) -> DMat3 {
    let (s, c) = deg.to_radians().sin_cos();
    DMat3::from_cols(DVec3::X, DVec3::new(0.0, c, s), DVec3::new(0.0, -s, c))
}

/// Rotation about y: (x cos + z sin, y, −x sin + z cos).
fn rot_y(deg: f64) -> DMat3 {
    let (s, c) = deg.to_radians().sin_cos();
    DMat3::from_cols(DVec3::new(c, 0.0, -s), DVec3::Y, DVec3::new(s, 0.0, c))
}

/// Rotation about z: (x cos − y sin, x sin + y cos, z).
fn rot_z(deg: f64) -> DMat3 {
    let (s, c) = deg.to_radians().sin_cos();
    DMat3::from_cols(DVec3::new(c, s, 0.0), DVec3::new(-s, c, 0.0), DVec3::Z)
}

// ------------------------------------------------------------------------------------------
// Assertions
// ------------------------------------------------------------------------------------------

/// Each channel within `rel` of the expected value, relative to max(|want|, 0.01).
fn assert_close(got: Vec3, want: DVec3, rel: f64, what: impl Display) {
    for c in 0..3 {
        let (g, w) = (got[c] as f64, want[c]);
        assert!(
            (g - w).abs() <= rel * w.abs().max(0.01),
            "{what}: got {got}, want {want} (channel {c}, tolerance {rel} relative)"
        );
    }
}

/// Each channel within `tol` of the expected value.
fn assert_abs(got: Vec3, want: DVec3, tol: f64, what: impl Display) {
    for c in 0..3 {
        assert!(
            (got[c] as f64 - want[c]).abs() <= tol,
            "{what}: got {got}, want {want} (channel {c}, tolerance {tol})"
        );
    }
}

// ------------------------------------------------------------------------------------------
// Seed light model
// ------------------------------------------------------------------------------------------

#[test]
fn point_light_on_a_plane_seed_model() {
    // L = k_a·I_a + color·intensity·k_d·max(0, n·l) at every pixel; the camera is off-axis and
    // the film not square, so n·l and the hit points vary across the image.
    let cam = Cam::new(rgb(0.5, -1.0, 4.0), DVec3::ZERO, 50.0, 8, 6);
    let mat = Mat::diffuse(rgb(0.3, 0.2, 0.1), rgb(0.6, 0.5, 0.4));
    let ia = rgb(0.2, 0.25, 0.3);
    let (light, color, intensity) = (rgb(1.0, 2.0, 3.0), rgb(1.0, 0.8, 0.6), 1.5);
    let text = cam.toml()
        + &render_section(&format!("ambient = {}", v3(ia)))
        + &mat.toml("m")
        + &point_light_toml(light, color, intensity)
        + &floor_toml("m");
    let film = render_text(&text);
    let n = DVec3::Z;
    let mut min_cos: f64 = 1.0;
    for (i, j) in cam.pixels() {
        let ray = cam.pixel(i, j);
        let (t, _, _) = parallelogram_coords(ray.o, ray.d, DVec3::ZERO, DVec3::X, DVec3::Y)
            .expect("every pixel sees the floor");
        assert!(t > 0.0);
        let x = ray.o + t * ray.d;
        let l = (light - x).normalize();
        min_cos = min_cos.min(n.dot(l));
        let want = mat.ka * ia + color * intensity * mat.kd * n.dot(l).max(0.0);
        assert_close(film.get(i, j), want, TOL, format!("pixel ({i}, {j})"));
    }
    assert!(min_cos < 0.9, "the test should cover n·l well below 1");
}

#[test]
fn full_shadow_keeps_only_the_ambient_term() {
    // A small blocker halfway between the light and the floor's center. Shadowed points get
    // k_a·I_a exactly; the others the full diffuse term.
    let cam = Cam::new(rgb(0.0, 0.0, 4.0), DVec3::ZERO, 40.0, 8, 8);
    let mat = Mat::diffuse(grey(0.4), rgb(0.8, 0.7, 0.6));
    let ia = grey(0.15);
    let light = rgb(3.0, 0.0, 3.0);
    let (bc, bu, bv) = (rgb(1.2, -0.3, 1.5), rgb(0.6, 0.0, 0.0), rgb(0.0, 0.6, 0.0));
    let text = cam.toml()
        + &render_section(&format!("ambient = {}", v3(ia)))
        + &mat.toml("m")
        + &point_light_toml(light, DVec3::ONE, 1.0)
        + &floor_toml("m")
        + &quad_toml("m", bc, bu, bv);
    let film = render_text(&text);
    let (mut shadowed, mut lit) = (0, 0);
    for (i, j) in cam.pixels() {
        let ray = cam.pixel(i, j);
        if crossing(ray.o, ray.d, (0.0, f64::INFINITY), bc, bu, bv, 0.01) != Crossing::Outside {
            continue; // the camera sees the blocker (or nearly)
        }
        let (t, _, _) =
            parallelogram_coords(ray.o, ray.d, DVec3::ZERO, DVec3::X, DVec3::Y).unwrap();
        let x = ray.o + t * ray.d;
        let Some(blocked) = blocks(x, light, bc, bu, bv) else {
            continue;
        };
        let want = if blocked {
            shadowed += 1;
            mat.ka * ia
        } else {
            lit += 1;
            mat.ka * ia + mat.kd * DVec3::Z.dot((light - x).normalize())
        };
        assert_close(film.get(i, j), want, TOL, format!("pixel ({i}, {j})"));
    }
    assert!(shadowed >= 4 && lit >= 20, "shadowed {shadowed}, lit {lit}");
    // The pixels around the image center are in the shadow.
    assert_close(film.get(4, 4), mat.ka * ia, TOL, "center pixel");
}

#[test]
fn half_occluded_area_light_gives_half_its_light() {
    // A 4×4 area light 2 above the origin; a blocker at height 1 covers x < 0, so as seen from
    // the origin it hides exactly the two sample columns with x < 0 (their shadow rays cross
    // height 1 at x = −0.375 and −0.125; the others at +0.125 and +0.375). By symmetry about
    // x = 0 the visible half carries half the unoccluded diffuse sum.
    let cam = Cam::probe(rgb(3.0, 0.0, 4.0), DVec3::ZERO);
    let mat = Mat::diffuse(rgb(0.3, 0.3, 0.2), rgb(0.7, 0.6, 0.5));
    let ia = grey(0.1);
    let light = AreaLight {
        center: rgb(0.0, 0.0, 2.0),
        u: rgb(2.0, 0.0, 0.0),
        v: rgb(0.0, 2.0, 0.0),
        n: 4,
        color: rgb(1.0, 0.9, 0.8),
        intensity: 2.0,
    };
    let (bc, bu, bv) = (rgb(-3.0, -0.5, 1.0), rgb(3.0, 0.0, 0.0), rgb(0.0, 1.0, 0.0));
    let base = cam.toml()
        + &render_section(&format!("ambient = {}", v3(ia)))
        + &mat.toml("m")
        + &light.toml()
        + &floor_toml("m");
    let x = DVec3::ZERO; // the probe's ray hits look_at
    let n = DVec3::Z;
    // The camera ray does not see the blocker (it crosses height 1 at x = 0.75).
    let ray = cam.pixel(0, 0);
    assert_eq!(
        crossing(ray.o, ray.d, (0.0, 1e9), bc, bu, bv, 0.01),
        Crossing::Outside
    );

    // The sums over the 16 sample points, by hand from the SPEC's sample-point formula.
    let (mut all, mut visible, mut hidden) = (DVec3::ZERO, DVec3::ZERO, 0);
    for y in light.samples() {
        let term = light.seed_weight() * mat.kd * n.dot((y - x).normalize()).max(0.0);
        all += term;
        match blocks(x, y, bc, bu, bv) {
            Some(true) => hidden += 1,
            Some(false) => visible += term,
            None => panic!("sample {y} grazes the blocker's edge"),
        }
    }
    assert_eq!(hidden, 8, "the blocker hides two of the four columns");
    assert!((visible - 0.5 * all).abs().max_element() < 1e-12);

    let open = render_text(&base).get(0, 0);
    assert_close(open, mat.ka * ia + all, TOL, "unoccluded");
    let half = render_text(&(base + &quad_toml("m", bc, bu, bv))).get(0, 0);
    assert_close(half, mat.ka * ia + visible, TOL, "half occluded");
    assert_close(
        half,
        mat.ka * ia + 0.5 * all,
        TOL,
        "half occluded = half the light",
    );
}

/// Renders the origin of the floor, seen from `eye`, under a white point light at `light`
/// (intensity 1) with material `mat`, and returns the pixel.
fn probe_floor(eye: DVec3, light: DVec3, mat: &Mat, ia: DVec3, render_extra: &str) -> Vec3 {
    let cam = Cam::probe(eye, DVec3::ZERO);
    let text = cam.toml()
        + &render_section(&format!("ambient = {}\n{render_extra}", v3(ia)))
        + &mat.toml("m")
        + &point_light_toml(light, DVec3::ONE, 1.0)
        + &floor_toml("m");
    render_text(&text).get(0, 0)
}

#[test]
fn phong_and_blinn_phong_specular() {
    // Shading point at the origin, n = +z. Light at (2, 0, 2): l = (1, 0, 1)/√2, n·l = 1/√2.
    // Camera straight above: v = +z. Then r = 2(n·l)n − l = (−1, 0, 1)/√2, so r·v = 1/√2, and
    // h = normalize(l + v) lies 22.5° from n, so n·h = cos(π/8).
    let ia = rgb(0.2, 0.2, 0.2);
    let above = rgb(0.0, 0.0, 2.0);
    let light = rgb(2.0, 0.0, 2.0);
    let mut mat = Mat {
        ka: rgb(0.3, 0.3, 0.3),
        kd: rgb(0.5, 0.4, 0.3),
        ks: rgb(0.4, 0.3, 0.2),
        p: 8.0,
    };
    let ambient = mat.ka * ia;
    let diffuse = mat.kd * FRAC_1_SQRT_2;

    // (1/√2)^8 = 1/16.
    let got = probe_floor(above, light, &mat, ia, "shading = \"phong\"");
    assert_close(got, ambient + diffuse + mat.ks / 16.0, TOL, "phong p = 8");
    let got = probe_floor(above, light, &mat, ia, "shading = \"blinn-phong\"");
    let want = ambient + diffuse + mat.ks * (PI / 8.0).cos().powi(8);
    assert_close(got, want, TOL, "blinn-phong p = 8");

    // A viewer on the light's side, low: r·v < 0, so Phong's specular vanishes for p > 0 and is
    // k_s·0⁰ = k_s for p = 0.
    let low = rgb(3.0, 0.0, 1.0);
    let v = low.normalize();
    let r = rgb(-1.0, 0.0, 1.0) * FRAC_1_SQRT_2;
    assert!(r.dot(v) < -0.3);
    let got = probe_floor(low, light, &mat, ia, "shading = \"phong\"");
    assert_close(got, ambient + diffuse, TOL, "phong, r·v < 0");
    mat.p = 0.0;
    let got = probe_floor(low, light, &mat, ia, "shading = \"phong\"");
    assert_close(
        got,
        ambient + diffuse + mat.ks,
        TOL,
        "phong p = 0 (0^0 = 1)",
    );
    let got = probe_floor(above, light, &mat, ia, "shading = \"blinn-phong\"");
    assert_close(got, ambient + diffuse + mat.ks, TOL, "blinn-phong p = 0");

    // The light below the floor: n·l < 0, so B = 0 and only the ambient term is left, even with
    // p = 0, whose specular factor would otherwise be 1 whatever the angle.
    let below = rgb(1.0, 0.0, -1.0);
    for shading in ["phong", "blinn-phong"] {
        let got = probe_floor(above, below, &mat, ia, &format!("shading = \"{shading}\""));
        assert_close(got, ambient, TOL, format!("{shading}, light behind"));
    }
}

#[test]
fn specular_matches_the_general_formula_across_an_image() {
    // The same (Blinn-)Phong sums as above, but at every pixel of a small image, against the
    // general formula (v = −d, r = 2(n·l)n − l, h = normalize(l + v)).
    let cam = Cam::new(rgb(-1.0, -0.5, 2.5), DVec3::ZERO, 60.0, 7, 5);
    let mat = Mat {
        ka: rgb(0.2, 0.3, 0.4),
        kd: rgb(0.5, 0.4, 0.3),
        ks: rgb(0.6, 0.5, 0.4),
        p: 12.0,
    };
    let ia = grey(0.1);
    let light = rgb(1.0, 0.5, 2.0);
    for (shading, blinn) in [("phong", false), ("blinn-phong", true)] {
        let text = cam.toml()
            + &render_section(&format!("ambient = {}\nshading = \"{shading}\"", v3(ia)))
            + &mat.toml("m")
            + &point_light_toml(light, DVec3::ONE, 1.0)
            + &floor_toml("m");
        let film = render_text(&text);
        for (i, j) in cam.pixels() {
            let ray = cam.pixel(i, j);
            let (t, _, _) =
                parallelogram_coords(ray.o, ray.d, DVec3::ZERO, DVec3::X, DVec3::Y).unwrap();
            let x = ray.o + t * ray.d;
            let l = (light - x).normalize();
            let want = mat.ka * ia + seed_brdf(DVec3::Z, l, -ray.d, &mat, DVec3::ONE, blinn);
            assert_close(film.get(i, j), want, TOL, format!("{shading} ({i}, {j})"));
        }
    }
}

// ------------------------------------------------------------------------------------------
// Physical light model
// ------------------------------------------------------------------------------------------

#[test]
fn physical_point_light() {
    // E = color·intensity/d², B = k_d/π·cosθ; the ambient term still applies.
    let mat = Mat::diffuse(grey(0.2), grey(0.6));
    let ia = grey(0.05);
    let light = rgb(1.0, 0.0, 2.0);
    let (color, intensity) = (rgb(1.0, 0.5, 0.25), 10.0);
    let cam = Cam::probe(rgb(0.0, 0.0, 3.0), DVec3::ZERO);
    let text = cam.toml()
        + &render_section(&format!("ambient = {}\nlight_model = \"physical\"", v3(ia)))
        + &mat.toml("m")
        + &point_light_toml(light, color, intensity)
        + &floor_toml("m");
    // d² = 5, cosθ = 2/√5.
    let want = mat.ka * ia + color * intensity / 5.0 * mat.kd / PI * (2.0 / 5f64.sqrt());
    assert_close(render_text(&text).get(0, 0), want, TOL, "origin");

    // The whole image, with the inverse-square falloff varying across it.
    let cam = Cam::new(rgb(0.0, -2.0, 3.0), DVec3::ZERO, 70.0, 6, 4);
    let text = cam.toml()
        + &render_section(&format!("ambient = {}\nlight_model = \"physical\"", v3(ia)))
        + &mat.toml("m")
        + &point_light_toml(light, color, intensity)
        + &floor_toml("m");
    let film = render_text(&text);
    for (i, j) in cam.pixels() {
        let ray = cam.pixel(i, j);
        let (t, _, _) =
            parallelogram_coords(ray.o, ray.d, DVec3::ZERO, DVec3::X, DVec3::Y).unwrap();
        let x = ray.o + t * ray.d;
        let to = light - x;
        let l = to.normalize();
        let want = mat.ka * ia
            + color * intensity / to.length_squared()
                * physical_brdf(DVec3::Z, l, -ray.d, &mat, false);
        assert_close(film.get(i, j), want, TOL, format!("pixel ({i}, {j})"));
    }
}

#[test]
fn physical_specular_is_energy_normalized() {
    // The geometry of `phong_and_blinn_phong_specular`: n·l = r·v = 1/√2, n·h = cos(π/8),
    // d² = 8. Phong: (k_d/π + k_s·(p + 2)/(2π)·(1/√2)^p)·n·l; Blinn-Phong: (p + 8)/(8π).
    let ia = grey(0.1);
    let mat = Mat {
        ka: grey(0.2),
        kd: rgb(0.5, 0.4, 0.3),
        ks: rgb(0.4, 0.3, 0.2),
        p: 8.0,
    };
    let above = rgb(0.0, 0.0, 2.0);
    let light = rgb(2.0, 0.0, 2.0);
    let e = 1.0 / 8.0;
    let got = probe_floor(above, light, &mat, ia, "light_model = \"physical\"");
    let want =
        mat.ka * ia + e * (mat.kd / PI + mat.ks * (10.0 / (2.0 * PI)) / 16.0) * FRAC_1_SQRT_2;
    assert_close(got, want, TOL, "physical phong");
    let got = probe_floor(
        above,
        light,
        &mat,
        ia,
        "light_model = \"physical\"\nshading = \"blinn-phong\"",
    );
    let spec = (16.0 / (8.0 * PI)) * (PI / 8.0).cos().powi(8);
    let want = mat.ka * ia + e * (mat.kd / PI + mat.ks * spec) * FRAC_1_SQRT_2;
    assert_close(got, want, TOL, "physical blinn-phong");
}

#[test]
fn physical_area_light_is_one_sided_and_seed_area_light_is_not() {
    // A 1×1 light 2 above the origin, 2×2 samples. With u = x, v = y its normal u × v is +z:
    // it faces away from the floor, so the origin, behind its plane, gets only ambient light.
    // With u and v swapped it faces the floor. Under the seed model it lights both ways.
    let cam = Cam::probe(rgb(0.0, -1.0, 3.0), DVec3::ZERO);
    let mat = Mat::diffuse(grey(0.3), rgb(0.9, 0.8, 0.7));
    let ia = grey(0.1);
    let up = AreaLight {
        center: rgb(0.0, 0.0, 2.0),
        u: DVec3::X,
        v: DVec3::Y,
        n: 2,
        color: rgb(1.0, 1.0, 0.5),
        intensity: 20.0,
    };
    let down = AreaLight {
        u: DVec3::Y,
        v: DVec3::X,
        ..up
    };
    let scene = |light: &AreaLight, model: &str| {
        cam.toml()
            + &render_section(&format!("ambient = {}\nlight_model = \"{model}\"", v3(ia)))
            + &mat.toml("m")
            + &light.toml()
            + &floor_toml("m")
    };
    let x = DVec3::ZERO;
    let v = (cam.eye - x).normalize();
    let n = DVec3::Z;

    let got = render_text(&scene(&up, "physical")).get(0, 0);
    assert_close(got, mat.ka * ia, TOL, "physical, behind the light");

    let mut want = mat.ka * ia;
    for y in down.samples() {
        let l = (y - x).normalize();
        want += down.physical_e(x, y) * physical_brdf(n, l, v, &mat, false);
    }
    let got = render_text(&scene(&down, "physical")).get(0, 0);
    assert_close(got, want, TOL, "physical, in front of the light");

    for light in [up, down] {
        let mut want = mat.ka * ia;
        for y in light.samples() {
            let l = (y - x).normalize();
            want += light.seed_weight() * seed_brdf(n, l, v, &mat, DVec3::ONE, false);
        }
        let got = render_text(&scene(&light, "phong")).get(0, 0);
        assert_close(got, want, TOL, format!("seed model, light u = {}", light.u));
    }
}

#[test]
fn small_distant_area_light_approximates_a_point_light() {
    // A 0.05 × 0.05 light facing down at (2, 1, 5), 5.5 away from the origin: its E_s sum is
    // close to that of a point light at its center with intensity·area·cos_l (cos_l = −n_l·l =
    // 5/√30), and equal to the E_s formula summed over its 3×3 samples.
    let cam = Cam::probe(rgb(0.0, 0.0, 3.0), DVec3::ZERO);
    let mat = Mat::diffuse(grey(0.5), rgb(0.8, 0.6, 0.4));
    let light = AreaLight {
        center: rgb(2.0, 1.0, 5.0),
        u: rgb(0.05, 0.0, 0.0),
        v: rgb(0.0, -0.05, 0.0),
        n: 3,
        color: rgb(1.0, 0.9, 0.8),
        intensity: 30000.0,
    };
    assert!(light.u.cross(light.v).z < 0.0, "the light faces down");
    let head =
        cam.toml() + &render_section("ambient = 0\nlight_model = \"physical\"") + &mat.toml("m");
    let area = render_text(&(head.clone() + &light.toml() + &floor_toml("m"))).get(0, 0);

    let x = DVec3::ZERO;
    let (n, v) = (DVec3::Z, DVec3::Z);
    let mut exact = DVec3::ZERO;
    for y in light.samples() {
        exact += light.physical_e(x, y) * physical_brdf(n, (y - x).normalize(), v, &mat, false);
    }
    assert_close(area, exact, TOL, "E_s sum");

    let to = light.center - x;
    let cos_l = to.z / to.length();
    let a = light.u.cross(light.v).length();
    let approx = light.color * light.intensity * a * cos_l / to.length_squared()
        * physical_brdf(n, to.normalize(), v, &mat, false);
    assert_close(area, approx, 1e-3, "point-light approximation");
    let point = render_text(
        &(head
            + &point_light_toml(light.center, light.color, light.intensity * a * cos_l)
            + &floor_toml("m")),
    )
    .get(0, 0);
    assert_close(
        area,
        point.as_dvec3(),
        1e-3,
        "point light of intensity·area·cos_l",
    );
}

// ------------------------------------------------------------------------------------------
// Lights are not geometry; two-sidedness; background and ambient
// ------------------------------------------------------------------------------------------

#[test]
fn camera_rays_do_not_see_lights() {
    // The camera looks straight at an area light (facing it) and through a point light.
    let background = rgb(0.1, 0.2, 0.3);
    let cam = Cam::probe(rgb(0.0, 0.0, 5.0), DVec3::ZERO);
    let light = AreaLight {
        center: DVec3::ZERO,
        u: rgb(2.0, 0.0, 0.0),
        v: rgb(0.0, 2.0, 0.0),
        n: 2,
        color: DVec3::ONE,
        intensity: 5.0,
    };
    let lights = light.toml() + &point_light_toml(rgb(0.0, 0.0, 1.0), DVec3::ONE, 5.0);
    for model in ["phong", "physical"] {
        let head = cam.toml()
            + &render_section(&format!(
                "background = {}\nlight_model = \"{model}\"",
                v3(background)
            ))
            + &lights;
        // Something off to the side, and nothing at all.
        let aside = quad_toml("", rgb(50.0, 0.0, 0.0), DVec3::X, DVec3::Y);
        for objects in [aside.as_str(), ""] {
            let got = render_text(&(head.clone() + objects)).get(0, 0);
            assert_close(
                got,
                background,
                TOL,
                format!("{model}, objects: {objects:?}"),
            );
        }
    }
}

#[test]
fn lights_cast_no_shadows() {
    // An area light hangs between a point light and the floor: the floor gets both lights.
    // The area light faces up (u × v = +z), away from the floor; the seed model's samples
    // shine both ways, so it lights the floor too.
    let cam = Cam::probe(rgb(0.5, 0.0, 4.0), DVec3::ZERO);
    let mat = Mat::diffuse(grey(0.2), rgb(0.5, 0.6, 0.7));
    let ia = grey(0.1);
    let point = rgb(0.0, 0.0, 3.0);
    let area = AreaLight {
        center: rgb(0.0, 0.0, 1.5),
        u: DVec3::X,
        v: DVec3::Y,
        n: 2,
        color: DVec3::ONE,
        intensity: 0.8,
    };
    let text = cam.toml()
        + &render_section(&format!("ambient = {}", v3(ia)))
        + &mat.toml("m")
        + &point_light_toml(point, DVec3::ONE, 0.6)
        + &area.toml()
        + &floor_toml("m");
    let x = DVec3::ZERO;
    let mut want = mat.ka * ia + 0.6 * mat.kd; // the point light straight above: n·l = 1
    for y in area.samples() {
        want += area.seed_weight() * mat.kd * DVec3::Z.dot((y - x).normalize());
    }
    assert_close(render_text(&text).get(0, 0), want, TOL, "both lights");
}

#[test]
fn light_samples_default_and_override() {
    // `render.light_samples` is N for area lights that give none; a light's own `samples`
    // wins over it; the per-render override (RenderSettings::light_samples) sets N for every
    // area light. Each case must equal the seed-model sum over its own N×N cell centers.
    let cam = Cam::probe(rgb(0.0, 0.0, 3.0), DVec3::ZERO);
    let mat = Mat::diffuse(grey(0.3), rgb(0.8, 0.7, 0.6));
    let light = |n: u32| AreaLight {
        center: rgb(0.5, 0.3, 1.0),
        u: rgb(2.0, 0.0, 0.0),
        v: rgb(0.0, 1.5, 0.5),
        n,
        color: DVec3::ONE,
        intensity: 1.0,
    };
    let want = |n: u32| {
        let l = light(n);
        let mut sum = mat.ka * 0.1;
        for y in l.samples() {
            sum += l.seed_weight() * mat.kd * DVec3::Z.dot(y.normalize());
        }
        sum
    };
    // The N = 2 and N = 3 sums differ, so the cases below are told apart.
    assert!((want(2) - want(3)).abs().max_element() > 1e-3);
    let text = |render: &str, own: Option<u32>| {
        let mut light_toml = light(1).toml();
        light_toml = match own {
            Some(n) => light_toml.replace("samples = 1\n", &format!("samples = {n}\n")),
            None => light_toml.replace("samples = 1\n", ""),
        };
        cam.toml()
            + &render_section(&format!("ambient = 0.1\n{render}"))
            + &mat.toml("m")
            + &light_toml
            + &floor_toml("m")
    };
    let run = |text: &str, light_samples: Option<u32>| {
        let file = SceneFile::from_str(text, SceneFormat::Toml, "t.toml", ".").unwrap();
        let mut scene = file.build(0).unwrap_or_else(|e| panic!("{e}"));
        scene.settings.light_samples = light_samples;
        render_with(&scene, &RenderOptions::default()).get(0, 0)
    };
    let ov = |n: Option<u32>| n;
    assert_close(
        run(&text("", None), ov(None)),
        want(5),
        TOL,
        "default N = 5",
    );
    assert_close(
        run(&text("light_samples = 3", None), ov(None)),
        want(3),
        TOL,
        "render.light_samples",
    );
    assert_close(
        run(&text("light_samples = 3", Some(2)), ov(None)),
        want(2),
        TOL,
        "the light's own samples",
    );
    assert_close(
        run(&text("light_samples = 3", Some(2)), ov(Some(4))),
        want(4),
        TOL,
        "the override beats the light's own samples",
    );
}

#[test]
fn quads_are_lit_from_behind_with_the_normal_flipped() {
    // A quad facing +z (u × v = +z) seen from −z: n becomes −z, so a light on the viewer's side
    // lights it and a light on its front side (behind it for this viewer) does not.
    let mat = Mat::diffuse(grey(0.25), rgb(0.9, 0.5, 0.3));
    let ia = grey(0.2);
    let eye = rgb(0.0, 0.3, -3.0);
    let viewer_side = rgb(1.0, 0.5, -2.0);
    let got = probe_floor(eye, viewer_side, &mat, ia, "");
    let n = -DVec3::Z;
    let want = mat.ka * ia + mat.kd * n.dot(viewer_side.normalize());
    assert_close(got, want, TOL, "light on the viewer's side");
    let got = probe_floor(eye, rgb(1.0, 0.5, 2.0), &mat, ia, "");
    assert_close(got, mat.ka * ia, TOL, "light on the far side");
}

#[test]
fn smooth_normals_use_the_inverse_transpose_and_flip_toward_the_viewer() {
    // A triangle in z = 0 (e₁ × e₂ = +z) with vertex normals (1, 0, 1), scaled by (2, 1, 1).
    // SPEC §5: normals go through the inverse transpose diag(1/2, 1, 1): (1/2, 0, 1), that is
    // (1, 0, 2)/√5 (the plain scale would give (2, 0, 1)/√5). With the light at the eye on the
    // +z axis, n·l = 2/√5. Seen from −z both normals are negated: again n·l = 2/√5.
    let mat = Mat::diffuse(grey(0.2), rgb(0.7, 0.6, 0.5));
    let ia = grey(0.1);
    for eye in [rgb(0.0, 0.0, 4.0), rgb(0.0, 0.0, -4.0)] {
        let cam = Cam::probe(eye, DVec3::ZERO);
        let text = cam.toml()
            + &render_section(&format!("ambient = {}", v3(ia)))
            + &mat.toml("m")
            + &point_light_toml(eye, DVec3::ONE, 1.0)
            + "[[objects]]\ntype = \"triangle\"\nmaterial = \"m\"\n\
               vertices = [[-1, -1, 0], [1, -1, 0], [0, 1, 0]]\n\
               normals = [[1, 0, 1], [1, 0, 1], [1, 0, 1]]\nscale = [2, 1, 1]\n";
        let n = DVec3::new(1.0, 0.0, 2.0).normalize();
        let l = eye.normalize();
        let n_facing = if l.z < 0.0 { -n } else { n };
        let want = mat.ka * ia + mat.kd * n_facing.dot(l);
        assert_close(
            render_text(&text).get(0, 0),
            want,
            TOL,
            format!("eye {eye}"),
        );
    }
}

#[test]
fn background_and_ambient_as_colors_and_numbers() {
    // Two pixels: the left one misses everything (background), the right one sees a quad lit
    // only by ambient light (k_a·I_a; k_a defaults to k_d when not given).
    let cam = Cam::new(rgb(0.0, 0.0, 4.0), DVec3::ZERO, 60.0, 2, 1);
    let right_half = quad_toml(
        "m",
        rgb(0.0, -5.0, 0.0),
        rgb(5.0, 0.0, 0.0),
        rgb(0.0, 5.0, 0.0),
    );
    let scene = |render: &str, material: &str| {
        cam.toml() + &render_section(render) + "[materials.m]\n" + material + "\n\n" + &right_half
    };
    let film = render_text(&scene(
        "ambient = [0.1, 0.2, 0.4]\nbackground = [0.3, 0.5, 0.7]",
        "diffuse = 0.9\nambient = [0.5, 0.6, 0.7]",
    ));
    assert_close(film.get(0, 0), rgb(0.3, 0.5, 0.7), TOL, "background color");
    assert_close(film.get(1, 0), rgb(0.05, 0.12, 0.28), TOL, "k_a·I_a");

    let film = render_text(&scene(
        "ambient = 0.25\nbackground = 0.5",
        "diffuse = 0.9\nambient = 0.5",
    ));
    assert_close(film.get(0, 0), grey(0.5), TOL, "background number");
    assert_close(film.get(1, 0), grey(0.125), TOL, "ambient numbers");
    let as_arrays = render_text(&scene(
        "ambient = [0.25, 0.25, 0.25]\nbackground = [0.5, 0.5, 0.5]",
        "diffuse = 0.9\nambient = [0.5, 0.5, 0.5]",
    ));
    assert_eq!(bits(&film), bits(&as_arrays), "a number means grey");

    let film = render_text(&scene(
        "ambient = [0.1, 0.2, 0.4]",
        "diffuse = [0.2, 0.4, 0.6]",
    ));
    assert_close(film.get(0, 0), DVec3::ZERO, TOL, "default background");
    assert_close(
        film.get(1, 0),
        rgb(0.02, 0.08, 0.24),
        TOL,
        "k_a defaults to k_d",
    );
}

// ------------------------------------------------------------------------------------------
// Pixel sampling
// ------------------------------------------------------------------------------------------

/// A 4×4 film looking down at the floor region x ≥ 0.6, y ≤ 0.8 (a quad's corner), lit by a
/// point light, over a colored background. With fov 90 from height 4, film point (x, y) sees
/// the floor at (2x − 4, 4 − 2y): the quad's edges fall inside pixel column 2 (film x = 2.3)
/// and pixel row 1 (film y = 1.6).
struct EdgeScene {
    cam: Cam,
    mat: Mat,
    ia: DVec3,
    light: DVec3,
    background: DVec3,
    corner: DVec3,
    u: DVec3,
    v: DVec3,
}

impl EdgeScene {
    fn new() -> Self {
        EdgeScene {
            cam: Cam::new(rgb(0.0, 0.0, 4.0), DVec3::ZERO, 90.0, 4, 4),
            mat: Mat::diffuse(grey(0.5), rgb(0.8, 0.7, 0.6)),
            ia: grey(0.1),
            light: rgb(2.0, 1.0, 3.0),
            background: rgb(0.2, 0.3, 0.4),
            corner: rgb(0.6, -10.0, 0.0),
            u: rgb(10.0, 0.0, 0.0),
            v: rgb(0.0, 10.8, 0.0),
        }
    }

    fn toml(&self, render: &str) -> String {
        self.cam.toml()
            + &format!(
                "[render]\n{render}\nambient = {}\nbackground = {}\n\n",
                v3(self.ia),
                v3(self.background)
            )
            + &self.mat.toml("m")
            + &point_light_toml(self.light, DVec3::ONE, 1.0)
            + &quad_toml("m", self.corner, self.u, self.v)
    }

    /// The radiance of the camera ray through film point (x, y), and whether it hit.
    fn sample(&self, x: f64, y: f64) -> (DVec3, bool) {
        let ray = self.cam.ray(x, y);
        match crossing(ray.o, ray.d, (0.0, 1e9), self.corner, self.u, self.v, 1e-4) {
            Crossing::Inside(t, _, _) => {
                let p = ray.o + t * ray.d;
                let l = (self.light - p).normalize();
                let b = seed_brdf(DVec3::Z, l, -ray.d, &self.mat, DVec3::ONE, false);
                (self.mat.ka * self.ia + b, true)
            }
            Crossing::Outside => (self.background, false),
            Crossing::Edge => panic!("sample ({x}, {y}) lies on the quad's edge"),
        }
    }

    /// SPEC §4: the plain mean of the samples at the given offsets from the pixel center, and
    /// how many of them hit the quad.
    fn pixel(&self, i: u32, j: u32, offsets: &[DVec2]) -> (DVec3, usize) {
        let mut sum = DVec3::ZERO;
        let mut hits = 0;
        for o in offsets {
            let (c, hit) = self.sample(i as f64 + 0.5 + o.x, j as f64 + 0.5 + o.y);
            sum += c;
            hits += hit as usize;
        }
        (sum / offsets.len() as f64, hits)
    }
}

/// SPEC §4 `grid`: ((k + ½)/n − ½, (l + ½)/n − ½).
fn grid_offsets(n: u32) -> Vec<DVec2> {
    let nf = n as f64;
    (0..n)
        .flat_map(|k| (0..n).map(move |l| (k, l)))
        .map(|(k, l)| DVec2::new((k as f64 + 0.5) / nf - 0.5, (l as f64 + 0.5) / nf - 0.5))
        .collect()
}

/// SPEC §4 `rgss`: the grid offsets rotated by θ = arctan(1/2), wrapped into [−½, ½).
fn rgss_offsets(n: u32) -> Vec<DVec2> {
    let theta = (0.5f64).atan();
    let (s, c) = theta.sin_cos();
    let wrap = |x: f64| {
        if x >= 0.5 {
            x - 1.0
        } else if x < -0.5 {
            x + 1.0
        } else {
            x
        }
    };
    grid_offsets(n)
        .into_iter()
        .map(|d| DVec2::new(wrap(d.x * c - d.y * s), wrap(d.x * s + d.y * c)))
        .collect()
}

#[test]
fn rgss_offsets_are_the_specs() {
    // The four offsets SPEC §4 lists for 4 samples (to its 4 decimals).
    let mut listed = vec![
        DVec2::new(0.1118, 0.3354),
        DVec2::new(-0.3354, 0.1118),
        DVec2::new(-0.1118, -0.3354),
        DVec2::new(0.3354, -0.1118),
    ];
    for o in rgss_offsets(2) {
        let i = listed
            .iter()
            .position(|e| (*e - o).abs().max_element() < 1e-4)
            .unwrap_or_else(|| panic!("{o} is not listed"));
        listed.remove(i);
    }
}

#[test]
fn grid_and_rgss_pixels_are_the_mean_of_their_samples() {
    let scene = EdgeScene::new();
    for (sampler, n, offsets) in [
        ("grid", 2, grid_offsets(2)),
        ("grid", 3, grid_offsets(3)),
        ("rgss", 2, rgss_offsets(2)),
        ("rgss", 3, rgss_offsets(3)),
    ] {
        let film =
            render_text(&scene.toml(&format!("sampler = \"{sampler}\"\nsamples = {}", n * n)));
        let mut straddling = 0;
        for (i, j) in scene.cam.pixels() {
            let (want, hits) = scene.pixel(i, j, &offsets);
            if hits > 0 && hits < offsets.len() {
                straddling += 1;
            }
            assert_close(
                film.get(i, j),
                want,
                TOL,
                format!("{sampler} {n}×{n}, pixel ({i}, {j}), {hits} hits"),
            );
        }
        // Column 2 and row 1 straddle the quad's edges.
        assert!(
            straddling >= 3,
            "{sampler} {n}×{n}: {straddling} straddling pixels"
        );
    }
    // The corner pixel (2, 1): for 4 samples, grid hits with (+¼, +¼) only, rgss with
    // (0.1118, 0.3354) only, so the two differ.
    let (g, g_hits) = scene.pixel(2, 1, &grid_offsets(2));
    let (r, r_hits) = scene.pixel(2, 1, &rgss_offsets(2));
    assert_eq!((g_hits, r_hits), (1, 1));
    assert!((g - r).abs().max_element() > 1e-3);
}

#[test]
fn jittered_sampler_depends_on_the_seed_only() {
    let scene = EdgeScene::new();
    let text = |seed: u64| {
        scene.toml(&format!(
            "sampler = \"jittered\"\nsamples = 16\nseed = {seed}"
        ))
    };
    let a = render_text(&text(7));
    let b = render_text(&text(7));
    assert_eq!(bits(&a), bits(&b), "same seed, same image");
    let c = render_text(&text(8));
    assert_ne!(bits(&a), bits(&c), "another seed, another image");
    // The seed override is the same as the file's seed.
    let file = SceneFile::from_str(&text(7), SceneFormat::Toml, "t.toml", ".").unwrap();
    let mut overridden = file.build(0).unwrap();
    overridden.settings.seed = 8;
    assert_eq!(
        bits(&render_with(&overridden, &RenderOptions::default())),
        bits(&c)
    );
    // Pixels whose every sample misses are the background exactly, and the edge pixels lie
    // between the background and the lit floor.
    assert_close(a.get(0, 0), scene.background, TOL, "pixel (0, 0)");
    assert_ne!(
        bits(&a)[4 + 2],
        bits(&c)[4 + 2],
        "the edge pixel (2, 1) moves with the seed"
    );
}

// ------------------------------------------------------------------------------------------
// Determinism
// ------------------------------------------------------------------------------------------

#[test]
fn images_do_not_depend_on_threads_or_regions() {
    // Jittered pixels and jittered area-light samples, a film that is not a multiple of the
    // tile size, and a region that starts and ends off the tile grid.
    let cam = Cam::new(rgb(0.0, 1.5, 5.0), DVec3::ZERO, 50.0, 37, 21);
    let text = cam.toml()
        + "[render]\nsampler = \"jittered\"\nsamples = 4\nseed = 3\nambient = 0.05\n\n\
           [[lights]]\ntype = \"area\"\ncenter = [0, 3, 1]\nu = [1.5, 0, 0]\nv = [0, 0, 1.5]\n\
           samples = 3\njitter = true\n\n\
           [[objects]]\ntype = \"cube\"\ncenter = [-0.8, 0.5, 0]\nsize = 1\nrotate = [0, 30, 0]\n\n\
           [[objects]]\ntype = \"sphere\"\ncenter = [0.9, 0.5, 0.2]\nradius = 0.5\n\n"
        + &quad_toml(
            "",
            rgb(-5.0, 0.0, 5.0),
            rgb(10.0, 0.0, 0.0),
            rgb(0.0, 0.0, -10.0),
        );
    let scene = build_in(&text, Path::new("."));
    let one = render_with(
        &scene,
        &RenderOptions {
            threads: 1,
            ..RenderOptions::default()
        },
    );
    let two = render_with(
        &scene,
        &RenderOptions {
            threads: 2,
            ..RenderOptions::default()
        },
    );
    assert_eq!(bits(&one), bits(&two), "1 thread vs 2");
    let again = render_with(&scene, &RenderOptions::default());
    assert_eq!(bits(&one), bits(&again), "default threads");

    let region = PixelBounds {
        x0: 5,
        x1: 30,
        y0: 3,
        y1: 19,
    };
    let part = render_with(
        &scene,
        &RenderOptions {
            threads: 2,
            region: Some(region),
            ..RenderOptions::default()
        },
    );
    assert_eq!((part.width, part.height), (25, 16));
    for y in 0..part.height {
        for x in 0..part.width {
            let (a, b) = (part.get(x, y), one.get(x + region.x0, y + region.y0));
            assert_eq!(
                a.to_array().map(f32::to_bits),
                b.to_array().map(f32::to_bits),
                "region pixel ({x}, {y})"
            );
        }
    }
    // The scene is not trivially flat: the light's jitter and the edges show.
    let distinct: std::collections::HashSet<_> = bits(&one).into_iter().collect();
    assert!(distinct.len() > 100);
}

// ------------------------------------------------------------------------------------------
// Textures
// ------------------------------------------------------------------------------------------

/// The textured quad of the texture tests: corner (−1, −1, 0), u = (2, 0, 0), v = (0, 2, 0),
/// so the floor point (X, Y) has uv ((X + 1)/2, (Y + 1)/2); seen from (0, 0, 3).
struct TexScene {
    cam: Cam,
    mat: Mat,
    ia: DVec3,
    light: DVec3,
}

impl TexScene {
    fn new(width: u32) -> Self {
        TexScene {
            cam: Cam::new(rgb(0.0, 0.0, 3.0), DVec3::ZERO, 60.0, width, width),
            mat: Mat::diffuse(rgb(0.5, 0.5, 0.4), rgb(0.9, 0.8, 0.7)),
            ia: grey(0.2),
            light: rgb(0.3, 0.2, 2.5),
        }
    }

    fn toml(&self, texture: &str) -> String {
        self.cam.toml()
            + &render_section(&format!("ambient = {}", v3(self.ia)))
            + &format!(
                "[materials.m]\nambient = {}\ndiffuse = {}\ntexture = \"t\"\n\n[textures.t]\n{texture}\n\n",
                v3(self.mat.ka),
                v3(self.mat.kd)
            )
            + &point_light_toml(self.light, DVec3::ONE, 1.0)
            + &quad_toml(
                "m",
                rgb(-1.0, -1.0, 0.0),
                rgb(2.0, 0.0, 0.0),
                rgb(0.0, 2.0, 0.0),
            )
    }

    /// For each pixel whose ray hits the quad clearly inside: its uv and the expected radiance
    /// for texture color `t(uv)` (None: too close to a texel or check boundary to say), i.e.
    /// T·k_a·I_a + T·k_d·max(0, n·l). Pixels that clearly miss must be black (background 0).
    fn check(&self, film: &Film, tol: f64, t: impl Fn(DVec2) -> Option<DVec3>) -> usize {
        let mut checked = 0;
        for (i, j) in self.cam.pixels() {
            let ray = self.cam.pixel(i, j);
            let corner = rgb(-1.0, -1.0, 0.0);
            let (u, v) = (rgb(2.0, 0.0, 0.0), rgb(0.0, 2.0, 0.0));
            match crossing(ray.o, ray.d, (0.0, 1e9), corner, u, v, 1e-3) {
                Crossing::Inside(tt, a, b) => {
                    let Some(tex) = t(DVec2::new(a, b)) else {
                        continue;
                    };
                    let x = ray.o + tt * ray.d;
                    let l = (self.light - x).normalize();
                    let want = tex * self.mat.ka * self.ia + tex * self.mat.kd * l.z.max(0.0);
                    assert_abs(
                        film.get(i, j),
                        want,
                        tol,
                        format!("pixel ({i}, {j}), uv ({a}, {b})"),
                    );
                    checked += 1;
                }
                Crossing::Outside => assert_abs(film.get(i, j), DVec3::ZERO, 0.0, "miss"),
                Crossing::Edge => {}
            }
        }
        checked
    }
}

/// Integer part, or None when `x` is within 1e-3 of an integer (a boundary).
fn cell(x: f64) -> Option<i64> {
    let f = x.floor();
    (x - f > 1e-3 && f + 1.0 - x > 1e-3).then_some(f as i64)
}

#[test]
fn checker_texture() {
    // SPEC §6: st = uv·uv_scale + uv_offset; `even` where floor(s·checks) + floor(t·checks) is
    // even, else `odd`; T multiplies k_a and k_d.
    let scene = TexScene::new(16);
    let (even, odd) = (rgb(0.9, 0.8, 0.1), rgb(0.1, 0.2, 0.7));
    let (checks, scale, offset) = (3.0, DVec2::new(1.0, 2.0), DVec2::new(0.1, -0.35));
    let texture = format!(
        "type = \"checker\"\neven = {}\nodd = {}\nchecks = {checks:?}\nuv_scale = [{:?}, {:?}]\n\
         uv_offset = [{:?}, {:?}]",
        v3(even),
        v3(odd),
        scale.x,
        scale.y,
        offset.x,
        offset.y
    );
    let film = render_text(&scene.toml(&texture));
    let checked = scene.check(&film, TOL, |uv| {
        let st = uv * scale + offset;
        let sum = cell(st.x * checks)? + cell(st.y * checks)?;
        Some(if sum.rem_euclid(2) == 0 { even } else { odd })
    });
    assert!(checked >= 80, "{checked} pixels checked");
}

/// A 2×2 PNG, row 0 at the top: red, green / blue, orange-ish.
const TEXELS: [[[u8; 3]; 2]; 2] = [[[255, 0, 0], [0, 128, 0]], [[0, 0, 64], [200, 100, 50]]];

/// A fresh folder holding the texture [`TEXELS`] as `tex.png`.
fn texture_dir(name: &str) -> TempDir {
    let dir = TempDir::new(name);
    dir.png("tex.png", 2, 2, |x, y| TEXELS[y as usize][x as usize]);
    dir
}

/// Texel (column x, row y from the top), decoded to linear.
fn texel(x: usize, y: usize, srgb: bool) -> DVec3 {
    let c = TEXELS[y][x].map(|b| {
        let v = b as f64 / 255.0;
        if srgb {
            srgb_to_linear(v)
        } else {
            v
        }
    });
    DVec3::from(c)
}

#[test]
fn image_texture_nearest_across_the_quad() {
    // uv_scale 2 and offset −½ make st run over [−½, 1½]: the image repeats (Euclidean modulo,
    // negative st included) or clamps. SPEC §6 `nearest`: texel (floor(s·W), floor((1 − t)·H)).
    let dir = texture_dir("nearest");
    let scene = TexScene::new(20);
    for (wrap, colorspace) in [("repeat", "srgb"), ("clamp", "srgb"), ("repeat", "linear")] {
        let texture = format!(
            "type = \"image\"\nfile = \"tex.png\"\nfilter = \"nearest\"\nwrap = \"{wrap}\"\n\
             colorspace = \"{colorspace}\"\nuv_scale = [2, 2]\nuv_offset = [-0.5, -0.5]"
        );
        let film = render_in(&scene.toml(&texture), dir.path());
        let index = |i: i64| -> usize {
            if wrap == "repeat" {
                i.rem_euclid(2) as usize
            } else {
                i.clamp(0, 1) as usize
            }
        };
        let checked = scene.check(&film, TEX_TOL, |uv| {
            let st = uv * 2.0 - 0.5;
            let x = cell(st.x * 2.0)?;
            let y = cell((1.0 - st.y) * 2.0)?;
            Some(texel(index(x), index(y), colorspace == "srgb"))
        });
        assert!(
            checked >= 120,
            "{wrap}/{colorspace}: {checked} pixels checked"
        );
    }
}

#[test]
fn image_texture_bilinear_across_the_quad() {
    // SPEC §6 `bilinear`: x = s·W − ½, y = (1 − t)·H − ½; the four texels around (x, y),
    // wrapped or clamped, each decoded to linear, weighted by x − floor(x) and y − floor(y).
    // The blend is continuous in uv, so every pixel on the quad is checked.
    let dir = texture_dir("bilinear-quad");
    let scene = TexScene::new(20);
    for (wrap, colorspace) in [("repeat", "srgb"), ("clamp", "srgb"), ("clamp", "linear")] {
        let texture = format!(
            "type = \"image\"\nfile = \"tex.png\"\nfilter = \"bilinear\"\nwrap = \"{wrap}\"\n\
             colorspace = \"{colorspace}\"\nuv_scale = [1.5, 2]\nuv_offset = [-0.3, -0.6]"
        );
        let film = render_in(&scene.toml(&texture), dir.path());
        let index = |i: f64| -> usize {
            let i = i as i64;
            if wrap == "repeat" {
                i.rem_euclid(2) as usize
            } else {
                i.clamp(0, 1) as usize
            }
        };
        let srgb = colorspace == "srgb";
        let checked = scene.check(&film, TEX_TOL, |uv| {
            let st = uv * DVec2::new(1.5, 2.0) + DVec2::new(-0.3, -0.6);
            let x = st.x * 2.0 - 0.5;
            let y = (1.0 - st.y) * 2.0 - 0.5;
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = (x - x0, y - y0);
            let t = |dx: f64, dy: f64| texel(index(x0 + dx), index(y0 + dy), srgb);
            let top = t(0.0, 0.0) * (1.0 - fx) + t(1.0, 0.0) * fx;
            let bottom = t(0.0, 1.0) * (1.0 - fx) + t(1.0, 1.0) * fx;
            Some(top * (1.0 - fy) + bottom * fy)
        });
        assert!(
            checked >= 120,
            "{wrap}/{colorspace}: {checked} pixels checked"
        );
    }
}

#[test]
fn image_texture_t_zero_is_the_bottom_row() {
    // Probes at the centers of the four quadrants of the quad (uv ¼ or ¾), where the nearest
    // texel is plain; t = 0 is the bottom row of the image (as in OBJ).
    let dir = texture_dir("bottom-row");
    let mat = Mat::diffuse(grey(0.5), rgb(0.9, 0.8, 0.7));
    let ia = grey(0.2);
    for (uv, name, (x, y)) in [
        (DVec2::new(0.25, 0.25), "bottom left (0, 0, 64)", (0, 1)),
        (
            DVec2::new(0.75, 0.25),
            "bottom right (200, 100, 50)",
            (1, 1),
        ),
        (DVec2::new(0.25, 0.75), "top left (255, 0, 0)", (0, 0)),
        (DVec2::new(0.75, 0.75), "top right (0, 128, 0)", (1, 0)),
    ] {
        // The quad (−1, −1)–(1, 1) has the floor point (2s − 1, 2t − 1) at uv (s, t).
        let target = rgb(2.0 * uv.x - 1.0, 2.0 * uv.y - 1.0, 0.0);
        let eye = target + rgb(0.0, 0.0, 3.0);
        for colorspace in ["srgb", "linear"] {
            let text = Cam::probe(eye, target).toml()
                + &render_section(&format!("ambient = {}", v3(ia)))
                + &format!(
                    "[materials.m]\nambient = {}\ndiffuse = {}\ntexture = \"t\"\n\n\
                     [textures.t]\ntype = \"image\"\nfile = \"tex.png\"\nfilter = \"nearest\"\n\
                     colorspace = \"{colorspace}\"\n\n",
                    v3(mat.ka),
                    v3(mat.kd)
                )
                + &point_light_toml(eye, DVec3::ONE, 1.0)
                + &quad_toml(
                    "m",
                    rgb(-1.0, -1.0, 0.0),
                    rgb(2.0, 0.0, 0.0),
                    rgb(0.0, 2.0, 0.0),
                );
            let t = texel(x, y, colorspace == "srgb");
            // The light at the eye: n·l = 1.
            let want = t * mat.ka * ia + t * mat.kd;
            let got = render_in(&text, dir.path()).get(0, 0);
            assert_abs(got, want, TEX_TOL, format!("{name}, {colorspace}"));
        }
    }
}

#[test]
fn image_texture_bilinear_blends_decoded_texels() {
    // At uv (½, ½) the bilinear lookup (x = s·W − ½ = ½, y = (1 − t)·H − ½ = ½) weighs all four
    // texels equally, after decoding each to linear; at (¼, ¾), a texel center, it is that texel.
    let dir = texture_dir("bilinear");
    let ia = grey(1.0);
    for (uv, want) in [
        (
            DVec2::new(0.5, 0.5),
            (texel(0, 0, true) + texel(1, 0, true) + texel(0, 1, true) + texel(1, 1, true)) / 4.0,
        ),
        (DVec2::new(0.25, 0.75), texel(0, 0, true)),
    ] {
        let target = rgb(2.0 * uv.x - 1.0, 2.0 * uv.y - 1.0, 0.0);
        // No lights: the pixel is T·k_a·I_a with k_a = I_a = 1, so it is T itself.
        let text = Cam::probe(target + rgb(0.0, 0.0, 3.0), target).toml()
            + &render_section(&format!("ambient = {}", v3(ia)))
            + "[materials.m]\nambient = 1\ntexture = \"t\"\n\n\
               [textures.t]\ntype = \"image\"\nfile = \"tex.png\"\n\n"
            + &quad_toml(
                "m",
                rgb(-1.0, -1.0, 0.0),
                rgb(2.0, 0.0, 0.0),
                rgb(0.0, 2.0, 0.0),
            );
        let got = render_in(&text, dir.path()).get(0, 0);
        assert_abs(got, want, TEX_TOL, format!("uv {uv}"));
    }
}

// ------------------------------------------------------------------------------------------
// Shapes and transforms
// ------------------------------------------------------------------------------------------

#[test]
fn sphere_seen_head_on() {
    // A unit sphere 5 in front of the camera, lit by a point light at the eye: l = −d for every
    // camera ray, so the pixel is k_a·I_a + k_d·(n·(−d)) with n the true sphere's normal at the
    // ray's hit (up to the tessellation, see SPHERE_TOL). Rays that miss the true sphere miss
    // its inscribed tessellation too. Mirrored (scale −1 along x) it is the same sphere: the
    // mirror reverses the triangles' winding but not the normals, which must still face out.
    let cam = Cam::new(rgb(0.0, 0.0, 5.0), DVec3::ZERO, 30.0, 16, 16);
    let mat = Mat::diffuse(grey(0.3), rgb(0.7, 0.6, 0.5));
    let ia = grey(0.1);
    let text = cam.toml()
        + &render_section(&format!("ambient = {}", v3(ia)))
        + &mat.toml("m")
        + &point_light_toml(cam.eye, DVec3::ONE, 1.0)
        + "[[objects]]\ntype = \"sphere\"\nmaterial = \"m\"\ncenter = [0, 0, 0]\nradius = 1\n";
    for scale in ["1", "[-1, 1, 1]"] {
        let film = render_text(&format!("{text}scale = {scale}\n"));
        let (mut hits, mut misses) = (0, 0);
        for (i, j) in cam.pixels() {
            let ray = cam.pixel(i, j);
            let tc = -ray.o.dot(ray.d); // closest approach to the center
            let b = (ray.o + tc * ray.d).length();
            if b < 0.9 {
                let t = tc - (1.0 - b * b).sqrt();
                let n = ray.o + t * ray.d;
                let want = mat.ka * ia + mat.kd * n.dot(-ray.d);
                assert_abs(
                    film.get(i, j),
                    want,
                    SPHERE_TOL,
                    format!("pixel ({i}, {j}), scale {scale}"),
                );
                hits += 1;
            } else if b > 1.0 {
                assert_abs(
                    film.get(i, j),
                    DVec3::ZERO,
                    0.0,
                    format!("pixel ({i}, {j}), scale {scale}"),
                );
                misses += 1;
            }
        }
        assert!(hits > 30 && misses > 100, "{hits} hits, {misses} misses");

        // Head-on, a hair off the axis (so as not to aim exactly at a vertex of the tessellation):
        // n·l = √(1 − b²) with b ≈ 0.016, which is 1 to 1.3e-4: the pixel is k_a·I_a + k_d·1.
        let probe = Cam::probe(cam.eye, rgb(0.01, 0.013, 0.0));
        let text = probe.toml()
            + &render_section(&format!("ambient = {}", v3(ia)))
            + &mat.toml("m")
            + &point_light_toml(cam.eye, DVec3::ONE, 1.0)
            + "[[objects]]\ntype = \"sphere\"\nmaterial = \"m\"\ncenter = [0, 0, 0]\nradius = 1\n";
        assert_abs(
            render_text(&text).get(0, 0),
            mat.ka * ia + mat.kd,
            1e-3,
            "head-on",
        );
    }
}

#[test]
fn rotated_cube_shows_its_edge_at_the_center_column() {
    // A 2-unit cube turned 45° about y: its +z face now faces (1, 0, 1)/√2 and its −x face
    // (−1, 0, 1)/√2; both planes are at distance 1 from the center, and they meet in the
    // vertical edge x = 0, z = √2, which the camera on the z axis sees at the center column.
    // A light at (3, 0, 3) lights the right face only: the left one keeps k_a·I_a.
    let cam = Cam::new(rgb(0.0, 0.0, 5.0), DVec3::ZERO, 40.0, 8, 8);
    let mat = Mat::diffuse(grey(0.4), rgb(0.8, 0.7, 0.6));
    let ia = grey(0.1);
    let light = rgb(3.0, 0.0, 3.0);
    let text = cam.toml()
        + &render_section(&format!("ambient = {}", v3(ia)))
        + &mat.toml("m")
        + &point_light_toml(light, DVec3::ONE, 1.0)
        + "[[objects]]\ntype = \"cube\"\nmaterial = \"m\"\ncenter = [0, 0, 0]\nsize = 2\n\
           rotate = [0, 45, 0]\n";
    let film = render_text(&text);
    let s = FRAC_1_SQRT_2;
    let faces = [
        (DVec3::new(s, 0.0, s), 0.0, 2f64.sqrt()), // right: x in [0, √2]
        (DVec3::new(-s, 0.0, s), -(2f64.sqrt()), 0.0), // left: x in [−√2, 0]
    ];
    let mut checked = 0;
    for (i, j) in cam.pixels() {
        let ray = cam.pixel(i, j);
        let mut want = None;
        let mut unsure = false;
        for (n, x0, x1) in faces {
            let t = (1.0 - n.dot(ray.o)) / n.dot(ray.d);
            let p = ray.o + t * ray.d;
            let m = 1e-3;
            if p.x > x0 + m && p.x < x1 - m && p.y.abs() < 1.0 - m {
                let l = (light - p).normalize();
                want = Some(mat.ka * ia + mat.kd * n.dot(l).max(0.0));
            } else if p.x > x0 - m && p.x < x1 + m && p.y.abs() < 1.0 + m {
                unsure = true;
            }
        }
        if unsure {
            continue;
        }
        let want = want.unwrap_or(DVec3::ZERO);
        assert_close(film.get(i, j), want, TOL, format!("pixel ({i}, {j})"));
        checked += 1;
    }
    assert!(checked >= 56, "{checked} pixels checked");
    for j in 2..6 {
        assert_close(
            film.get(3, j),
            mat.ka * ia,
            TOL,
            format!("left of the edge, row {j}"),
        );
        assert!(
            film.get(4, j).x > (mat.ka.x * ia.x) as f32 + 0.1,
            "right of the edge, row {j}"
        );
    }
}

/// Renders the point `target` seen from `eye` on a textured `object` (a TOML `[[objects]]`
/// body) with no lights, ambient 1 and k_a = 1: the pixel is the texture color T itself.
fn probe_texture_color(eye: DVec3, target: DVec3, texture: &str, object: &str) -> Vec3 {
    let text = Cam::probe(eye, target).toml()
        + &render_section("ambient = 1")
        + "[materials.m]\nambient = 1\ntexture = \"t\"\n\n[textures.t]\n"
        + texture
        + "\n\n[[objects]]\nmaterial = \"m\"\n"
        + object
        + "\n";
    render_text(&text).get(0, 0)
}

#[test]
fn cube_face_uvs_follow_the_spec() {
    // SPEC §2: each face's uvs span (0,0)–(1,1); on the side faces u runs to the right and v up
    // as seen from outside; on the top u runs along +x and v along −z; on the bottom u along +x
    // and v along +z. A checker with 2 checks per unit is `even` where floor(2s) + floor(2t) is
    // even: probing one point per face, at uv (¼, ¾), is `odd`; the mirrored u or v would be
    // `even`.
    let (even, odd) = (rgb(0.9, 0.1, 0.1), rgb(0.1, 0.1, 0.9));
    let texture = format!(
        "type = \"checker\"\neven = {}\nodd = {}\nchecks = 2",
        v3(even),
        v3(odd)
    );
    let cube = "type = \"cube\"\ncenter = [0, 0, 0]\nsize = 1";
    // (outward normal, the face point with uv (¼, ¾)) for a unit cube around the origin.
    let faces = [
        ("front +z", DVec3::Z, rgb(-0.25, 0.25, 0.5)), // u = x + ½, v = y + ½
        ("back −z", -DVec3::Z, rgb(0.25, 0.25, -0.5)), // right is −x: u = ½ − x
        ("right +x", DVec3::X, rgb(0.5, 0.25, 0.25)),  // right is −z: u = ½ − z
        ("left −x", -DVec3::X, rgb(-0.5, 0.25, -0.25)), // right is +z: u = z + ½
        ("top +y", DVec3::Y, rgb(-0.25, 0.5, -0.25)),  // u = x + ½, v = ½ − z
        ("bottom −y", -DVec3::Y, rgb(-0.25, -0.5, 0.25)), // u = x + ½, v = z + ½
    ];
    for (name, n, p) in faces {
        // Look at the face along its normal, a little off the axis so `up` is never parallel.
        let eye = p + 3.0 * n + rgb(0.01, 0.0, 0.01);
        let got = probe_texture_color(eye, p, &texture, cube);
        assert_close(got, odd, TOL, name);
    }
}

#[test]
fn sphere_uvs_follow_the_spec() {
    // SPEC §2: v runs from 0 at the bottom pole to 1 at the top; u is the azimuth from +x
    // toward −z over 2π. The point at azimuth 45° toward −z and polar angle 135° from the
    // bottom pole has uv (⅛, ¾): with 2 checks per unit, floor(¼) + floor(1½) = 1, `odd`. The
    // azimuth toward +z (u = ⅞) or v from the top (v = ¼) would give `even`.
    let (even, odd) = (rgb(0.9, 0.1, 0.1), rgb(0.1, 0.1, 0.9));
    let texture = format!(
        "type = \"checker\"\neven = {}\nodd = {}\nchecks = 2",
        v3(even),
        v3(odd)
    );
    let sphere = "type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1";
    let (theta, phi) = (0.75 * PI, 0.125 * 2.0 * PI);
    let p = DVec3::new(
        theta.sin() * phi.cos(),
        -theta.cos(),
        -theta.sin() * phi.sin(),
    );
    assert!(p.x > 0.0 && p.y > 0.0 && p.z < 0.0);
    let got = probe_texture_color(4.0 * p, p, &texture, sphere);
    assert_close(got, odd, TOL, "uv (1/8, 3/4)");
    // And the mirror images are `even`.
    for q in [DVec3::new(p.x, p.y, -p.z), DVec3::new(p.x, -p.y, p.z)] {
        let got = probe_texture_color(4.0 * q, q, &texture, sphere);
        assert_close(got, even, TOL, format!("mirror point {q}"));
    }
}

/// The world-space parallelogram of the object-space one under p' = T·Rz·Ry·Rx·S·p.
fn transformed(
    m: DMat3,
    translate: DVec3,
    (corner, u, v): (DVec3, DVec3, DVec3),
) -> (DVec3, DVec3, DVec3) {
    (m * corner + translate, m * u, m * v)
}

#[test]
fn transforms_apply_scale_then_rotate_x_y_z_then_translate() {
    // A quad in the object's xz-plane, scaled by (2, 1, ½), turned by (90°, 20°, 30°) and moved
    // by (0.3, −0.2, 0.5). Every pixel either clearly sees the parallelogram where
    // T·Rz·Ry·Rx·S puts it (ambient-lit: k_a·I_a = 0.5) or clearly misses it (background 0).
    let cam = Cam::new(rgb(0.0, 0.0, 4.0), DVec3::ZERO, 40.0, 24, 24);
    let (scale, rotate, translate) = (
        rgb(2.0, 1.0, 0.5),
        rgb(90.0, 20.0, 30.0),
        rgb(0.3, -0.2, 0.5),
    );
    let object = (rgb(-0.5, 0.0, 0.5), rgb(1.0, 0.0, 0.0), rgb(0.0, 0.0, -1.0));
    let text = cam.toml()
        + &render_section("ambient = 1")
        + "[materials.m]\nambient = 0.5\n\n"
        + &quad_toml("m", object.0, object.1, object.2)
        + &format!(
            "scale = {}\nrotate = {}\ntranslate = {}\n",
            v3(scale),
            v3(rotate),
            v3(translate)
        );
    let film = render_text(&text);
    let s = DMat3::from_diagonal(scale);
    let spec = rot_z(rotate.z) * rot_y(rotate.y) * rot_x(rotate.x) * s;
    let classify = |m: DMat3, i: u32, j: u32| {
        let (c, u, v) = transformed(m, translate, object);
        let ray = cam.pixel(i, j);
        crossing(ray.o, ray.d, (0.0, 1e9), c, u, v, 1e-3)
    };
    let (mut inside, mut outside) = (0, 0);
    for (i, j) in cam.pixels() {
        match classify(spec, i, j) {
            Crossing::Inside(..) => {
                inside += 1;
                assert_close(
                    film.get(i, j),
                    grey(0.5),
                    TOL,
                    format!("pixel ({i}, {j}) inside"),
                );
            }
            Crossing::Outside => {
                outside += 1;
                assert_close(
                    film.get(i, j),
                    DVec3::ZERO,
                    TOL,
                    format!("pixel ({i}, {j}) outside"),
                );
            }
            Crossing::Edge => {}
        }
    }
    assert!(
        inside > 30 && outside > 200,
        "{inside} inside, {outside} outside"
    );
    // The test tells the orders apart: other orders put the quad elsewhere.
    for (name, other) in [
        (
            "Rx·Ry·Rz·S",
            rot_x(rotate.x) * rot_y(rotate.y) * rot_z(rotate.z) * s,
        ),
        (
            "S·Rz·Ry·Rx",
            s * rot_z(rotate.z) * rot_y(rotate.y) * rot_x(rotate.x),
        ),
    ] {
        let differ = cam.pixels().any(|(i, j)| {
            matches!(
                (classify(spec, i, j), classify(other, i, j)),
                (Crossing::Inside(..), Crossing::Outside)
                    | (Crossing::Outside, Crossing::Inside(..))
            )
        });
        assert!(differ, "{name} gives the same picture");
    }
}

#[test]
fn cube_and_sphere_turn_and_scale_in_place_then_move_to_center() {
    // SPEC §2: cubes and spheres are built around the origin, transformed, then moved to their
    // `center`. A 1-unit cube scaled by (3, 1, 1) and turned 90° about z becomes 1 wide and 3
    // tall around its center (2, 0, 0): the probe at (2, 1.2) hits it, the one at (3.2, 0)
    // (where an unturned scaled cube would be) does not.
    let text = |target: DVec3| {
        Cam::probe(target + rgb(0.0, 0.0, 6.0), target).toml()
            + &render_section("ambient = 1")
            + "[materials.m]\nambient = 0.5\n\n\
               [[objects]]\ntype = \"cube\"\nmaterial = \"m\"\ncenter = [2, 0, 0]\nsize = 1\n\
               scale = [3, 1, 1]\nrotate = [0, 0, 90]\n"
    };
    assert_close(
        render_text(&text(rgb(2.0, 1.2, 0.0))).get(0, 0),
        grey(0.5),
        TOL,
        "inside",
    );
    assert_close(
        render_text(&text(rgb(3.2, 0.0, 0.0))).get(0, 0),
        DVec3::ZERO,
        TOL,
        "outside",
    );
}

// ------------------------------------------------------------------------------------------
// Output (SPEC §7)
// ------------------------------------------------------------------------------------------

#[test]
fn output_files_encode_as_the_spec_says() {
    // PNG: round(255·encode(clamp(c, 0, 1))), row 0 at the top; gamma: c^(1/gamma).
    // PFM: linear floats, unclamped, scanlines bottom to top. EXR: linear floats, unclamped.
    let dir = TempDir::new("output");
    let values = [
        [0.0, 0.5, 1.0],
        [0.18, 0.0031308, 0.002],
        [2.5, -0.5, 0.75],
        [0.04, 0.9, 0.3],
    ];
    let film = Film {
        width: 2,
        height: 2,
        pixels: values.iter().map(|&c| Vec3::from(c)).collect(),
        alpha: None,
    };
    let png = dir.join("out.png");
    for gamma in [None, Some(2.2f32)] {
        write_image(&film, &png, gamma).unwrap();
        let img = image::open(&png).unwrap().into_rgb8();
        assert_eq!(img.dimensions(), (2, 2));
        for (k, c) in values.iter().enumerate() {
            let (x, y) = (k as u32 % 2, k as u32 / 2);
            let want = c.map(|v| {
                let v = (v as f64).clamp(0.0, 1.0);
                let e = match gamma {
                    None => linear_to_srgb(v),
                    Some(g) => v.powf(1.0 / g as f64),
                };
                (255.0 * e).round() as u8
            });
            assert_eq!(
                img.get_pixel(x, y).0,
                want,
                "png pixel ({x}, {y}), gamma {gamma:?}"
            );
        }
    }

    let pfm = dir.join("out.pfm");
    write_image(&film, &pfm, None).unwrap();
    let bytes = std::fs::read(&pfm).unwrap();
    let header = b"PF\n2 2\n-1.0\n";
    assert_eq!(&bytes[..header.len()], header);
    let floats: Vec<f32> = bytes[header.len()..]
        .chunks(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect();
    // Bottom row (film row 1) first.
    let want: Vec<f32> = [values[2], values[3], values[0], values[1]]
        .iter()
        .flatten()
        .copied()
        .collect();
    assert_eq!(floats, want);

    let exr = dir.join("out.exr");
    write_image(&film, &exr, None).unwrap();
    let img = image::open(&exr).unwrap().into_rgb32f();
    for (k, c) in values.iter().enumerate() {
        let (x, y) = (k as u32 % 2, k as u32 / 2);
        assert_eq!(img.get_pixel(x, y).0, *c, "exr pixel ({x}, {y})");
    }
}

#[test]
fn a_light_sample_on_the_shaded_point_gives_no_nan() {
    // SPEC §5 leaves light samples lying exactly on a surface implementation-defined; whatever
    // the value, it must be a number, or EXR and PFM outputs would carry NaN.
    // The center pixel's ray (9×9, center sampler) hits the floor exactly at the light.
    let cam = Cam::new(rgb(0.0, 0.0, 2.0), DVec3::ZERO, 40.0, 9, 9);
    let text = cam.toml()
        + &render_section("ambient = 0.1")
        + &point_light_toml(DVec3::ZERO, DVec3::ONE, 1.0)
        + &floor_toml("");
    let film = render_text(&text);
    for (i, j) in cam.pixels() {
        assert!(
            film.get(i, j).is_finite(),
            "pixel ({i}, {j}): {}",
            film.get(i, j)
        );
    }
}
