#!/usr/bin/env python3
"""Render one scene with penumbra (light_model = "physical") and with Mitsuba 3, compare.

The scene is described once, below (SCENE), and translated into a penumbra TOML file and a
Mitsuba scene dictionary. Both renderers produce linear radiance; with ambient = 0, no specular
and a diffuse area emitter, penumbra's physical model is a stratified estimate of direct
lighting, which Mitsuba's `direct` integrator converges to. The images should agree up to
sampling noise: mean ratio penumbra/mitsuba ~ 1.00 per channel, no shift, no mirroring.

Usage (from the repository root, in an environment with `mitsuba` and `numpy`):

    python3 tools/mitsuba_compare/compare.py --penumbra target/release/penumbra

Outputs (scene file, both images as PFM, side-by-side and diff PNGs) go to --out
(default: a folder under the system temp dir), never into the repository.
Exit code 0 when the checks pass, 1 when they fail.
"""

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

# --------------------------------------------------------------------------------------------
# The scene, once. Lengths in scene units, angles in degrees, colors linear RGB.
# Deliberately asymmetric (cube left, light right of center, tilted second box) so that a
# mirrored image, a wrong rotation order or a shifted shadow shows up.
# --------------------------------------------------------------------------------------------
SCENE = {
    "width": 256,
    "height": 192,  # non-square: checks the aspect ratio
    "camera": {"position": [0.0, 3.0, 9.0], "look_at": [0.0, 1.0, 0.0], "up": [0.0, 1.0, 0.0],
               "fov": 40.0},
    "materials": {
        "floor": [0.7, 0.7, 0.7],
        "wall": [0.25, 0.45, 0.75],
        "box": [0.8, 0.35, 0.15],
        "tilted": [0.3, 0.75, 0.3],
    },
    "quads": [
        # u x v = x x z = -y: the floor's winding faces DOWN (checks two-sidedness).
        {"material": "floor", "corner": [-5.0, 0.0, -5.0], "u": [10.0, 0.0, 0.0],
         "v": [0.0, 0.0, 10.0]},
        # back wall, u x v = +z (faces the camera)
        {"material": "wall", "corner": [-5.0, 0.0, -5.0], "u": [10.0, 0.0, 0.0],
         "v": [0.0, 6.0, 0.0]},
    ],
    "cubes": [
        # standing on the floor, turned about y: casts a soft shadow
        {"material": "box", "center": [-1.0, 0.75, 0.3], "size": [1.5, 1.5, 1.5],
         "rotate": [0.0, 30.0, 0.0]},
        # floating, non-uniform size, turned about all three axes: checks p' = T·Rz·Ry·Rx·S·p
        {"material": "tilted", "center": [1.7, 1.3, -1.8], "size": [1.4, 0.5, 0.9],
         "rotate": [25.0, 40.0, 15.0]},
    ],
    # One rectangular light: center +- u/2 +- v/2, u x v = x x z = -y (faces down, toward the
    # scene). Radiance = color * intensity. Out of the camera's view.
    "light": {"center": [0.8, 4.5, 1.5], "u": [2.0, 0.0, 0.0], "v": [0.0, 0.0, 1.2],
              "color": [1.0, 0.95, 0.85], "intensity": 12.0, "samples": 32},
}


def vec(a):
    return np.asarray(a, dtype=np.float64)


def rot_x(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def affine(linear3, translation):
    m = np.eye(4)
    m[:3, :3] = linear3
    m[:3, 3] = translation
    return m


def parallelogram_to_world(center, u, v):
    """Mitsuba's rectangle spans [-1, 1]^2 in local xy with normal +z: map it onto
    center +- u/2 +- v/2 with local +z along normalize(u x v)."""
    u, v = vec(u), vec(v)
    n = np.cross(u, v)
    n = n / np.linalg.norm(n)
    return affine(np.column_stack([u / 2, v / 2, n]), vec(center))


def cube_to_world(c):
    """penumbra: the box of `size` around the origin, then Rz·Ry·Rx, then moved to `center`.
    Mitsuba's cube spans [-1, 1]^3, hence the scale by size/2."""
    rx, ry, rz = c["rotate"]
    lin = rot_z(rz) @ rot_y(ry) @ rot_x(rx) @ np.diag(vec(c["size"]) / 2)
    return affine(lin, vec(c["center"]))


# --------------------------------------------------------------------------------------------
# penumbra
# --------------------------------------------------------------------------------------------
def toml_vec(a):
    return "[" + ", ".join(repr(float(x)) for x in a) + "]"


def penumbra_toml(sc, spp):
    cam = sc["camera"]
    light = sc["light"]
    lines = [
        "[film]",
        f"width = {sc['width']}",
        f"height = {sc['height']}",
        "",
        "[camera]",
        f"position = {toml_vec(cam['position'])}",
        f"look_at = {toml_vec(cam['look_at'])}",
        f"up = {toml_vec(cam['up'])}",
        f"fov = {float(cam['fov'])!r}",
        "",
        "[render]",
        'sampler = "grid"',
        f"samples = {spp}",
        'light_model = "physical"',
        "ambient = 0",
        "background = 0",
        "",
    ]
    for name, kd in sc["materials"].items():
        lines += [f"[materials.{name}]", f"diffuse = {toml_vec(kd)}", "specular = 0", ""]
    lines += [
        "[[lights]]",
        'type = "area"',
        f"center = {toml_vec(light['center'])}",
        f"u = {toml_vec(light['u'])}",
        f"v = {toml_vec(light['v'])}",
        f"color = {toml_vec(light['color'])}",
        f"intensity = {float(light['intensity'])!r}",
        f"samples = {light['samples']}",
        "",
    ]
    for q in sc["quads"]:
        lines += ["[[objects]]", 'type = "quad"', f'material = "{q["material"]}"',
                  f"corner = {toml_vec(q['corner'])}", f"u = {toml_vec(q['u'])}",
                  f"v = {toml_vec(q['v'])}", ""]
    for c in sc["cubes"]:
        lines += ["[[objects]]", 'type = "cube"', f'material = "{c["material"]}"',
                  f"center = {toml_vec(c['center'])}", f"size = {toml_vec(c['size'])}",
                  f"rotate = {toml_vec(c['rotate'])}", ""]
    return "\n".join(lines)


def read_pfm(path):
    """Read a color PFM ('PF'): scale < 0 means little-endian; rows stored bottom to top.
    Returns float32 (H, W, 3) with row 0 at the top."""
    with open(path, "rb") as f:
        data = f.read()
    # header: three whitespace-separated tokens after the magic, each line ends with one '\n'
    parts = []
    pos = 0
    while len(parts) < 4:
        end = data.index(b"\n", pos)
        parts += data[pos:end].split()
        pos = end + 1
    magic, w, h, scale = parts[0], int(parts[1]), int(parts[2]), float(parts[3])
    if magic != b"PF":
        raise ValueError(f"{path}: not a color PFM (magic {magic!r})")
    dtype = "<f4" if scale < 0 else ">f4"
    img = np.frombuffer(data, dtype=dtype, count=w * h * 3, offset=pos).reshape(h, w, 3)
    return np.flipud(img).astype(np.float32)


def read_exr(path):
    import OpenEXR  # pip install openexr (only needed for --format exr)

    with OpenEXR.File(path) as f:
        ch = f.channels()
        if "RGB" in ch:
            return np.asarray(ch["RGB"].pixels, dtype=np.float32)
        return np.stack([np.asarray(ch[c].pixels, dtype=np.float32) for c in "RGB"], axis=-1)


def render_penumbra(exe, sc, spp, out_dir, fmt):
    scene_path = os.path.join(out_dir, "scene.toml")
    with open(scene_path, "w") as f:
        f.write(penumbra_toml(sc, spp))
    img_path = os.path.join(out_dir, f"penumbra.{fmt}")
    t0 = time.time()
    subprocess.run([exe, "render", scene_path, "-o", img_path, "--quiet"], check=True)
    dt = time.time() - t0
    img = read_pfm(img_path) if fmt == "pfm" else read_exr(img_path)
    return img, dt, scene_path


# --------------------------------------------------------------------------------------------
# Mitsuba
# --------------------------------------------------------------------------------------------
def sensor(mi, cam, width, height, spp):
    """Mitsuba's sensor for penumbra's pinhole `cam` (vertical `fov`): a box-filtered RGB film
    of `width × height` and `spp` independent samples a pixel."""
    return {
        "type": "perspective", "fov": float(cam["fov"]), "fov_axis": "y",
        "near_clip": 0.01, "far_clip": 1000.0,
        "to_world": mi.ScalarTransform4f().look_at(origin=cam["position"],
                                                   target=cam["look_at"], up=cam["up"]),
        "sampler": {"type": "independent", "sample_count": spp},
        "film": {"type": "hdrfilm", "width": width, "height": height, "pixel_format": "rgb",
                 "rfilter": {"type": "box"}},
    }


def mitsuba_scene(mi, sc, spp):
    T = mi.ScalarTransform4f
    cam = sc["camera"]

    def bsdf(kd):
        return {"type": "twosided",
                "material": {"type": "diffuse",
                             "reflectance": {"type": "rgb", "value": list(map(float, kd))}}}

    d = {
        "type": "scene",
        # direct lighting only (emitter + BSDF sampling with MIS); penumbra's lights are
        # invisible to camera rays, hence hide_emitters (the light is out of view anyway).
        "integrator": {"type": "direct", "hide_emitters": True},
        "sensor": sensor(mi, cam, sc["width"], sc["height"], spp),
    }
    for i, q in enumerate(sc["quads"]):
        c = vec(q["corner"]) + vec(q["u"]) / 2 + vec(q["v"]) / 2
        d[f"quad{i}"] = {"type": "rectangle",
                         "to_world": T(parallelogram_to_world(c, q["u"], q["v"]).tolist()),
                         "bsdf": bsdf(sc["materials"][q["material"]])}
    for i, c in enumerate(sc["cubes"]):
        d[f"cube{i}"] = {"type": "cube", "to_world": T(cube_to_world(c).tolist()),
                         "bsdf": bsdf(sc["materials"][c["material"]])}
    light = sc["light"]
    radiance = (vec(light["color"]) * light["intensity"]).tolist()
    d["light"] = {
        "type": "rectangle",
        # local +z = normalize(u x v): the side penumbra's physical area light emits toward;
        # Mitsuba's area emitter is one-sided toward the shape normal.
        "to_world": T(parallelogram_to_world(light["center"], light["u"], light["v"]).tolist()),
        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": radiance}},
        # black so that nothing reflects off the emitter itself
        "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}},
    }
    return d


def render_mitsuba(sc, spp, seed):
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    scene = mi.load_dict(mitsuba_scene(mi, sc, spp))
    t0 = time.time()
    img = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float32)
    return img[..., :3], time.time() - t0


# --------------------------------------------------------------------------------------------
# Comparison
# --------------------------------------------------------------------------------------------
def psnr(a, b, peak=1.0):
    mse = float(np.mean((a - b) ** 2))
    return float("inf") if mse == 0 else 10 * math.log10(peak * peak / mse)


def luminance(img):
    return img @ np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)


def srgb8(img):
    c = np.clip(img, 0, 1)
    c = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.round(c * 255).astype(np.uint8)


def write_png(path, img8):
    import mitsuba as mi

    mi.Bitmap(np.ascontiguousarray(img8), pixel_format=mi.Bitmap.PixelFormat.RGB).write(path)


def compare(p, m):
    """Metrics of penumbra image p against Mitsuba image m, both linear (H, W, 3)."""
    r = {}
    r["psnr_clip"] = psnr(np.clip(p, 0, 1), np.clip(m, 0, 1))
    peak = float(m.max())
    r["psnr_norm"] = psnr(p / peak, m / peak)
    r["ratio"] = [float(p[..., c].mean() / m[..., c].mean()) for c in range(3)]
    lum_m = luminance(m)
    lit = lum_m > 0.1 * float(np.percentile(lum_m, 99))
    r["lit_fraction"] = float(lit.mean())
    r["ratio_lit"] = [float(p[..., c][lit].sum() / m[..., c][lit].sum()) for c in range(3)]
    rel = np.abs(luminance(p) - lum_m)[lit] / lum_m[lit]
    r["mean_rel_lit"] = float(rel.mean())
    r["median_rel_lit"] = float(np.median(rel))
    # alignment: is the best match the identity, or a flip / a small shift?
    def mse(a, b):
        return float(np.mean((a - b) ** 2))
    cand = {"identity": mse(p, m), "flip_x": mse(p, m[:, ::-1]), "flip_y": mse(p, m[::-1])}
    best_shift, best = (0, 0), None
    k = 3
    for dy in range(-k, k + 1):
        for dx in range(-k, k + 1):
            a = p[k + dy:p.shape[0] - k + dy, k + dx:p.shape[1] - k + dx]
            b = m[k:m.shape[0] - k, k:m.shape[1] - k]
            e = mse(a, b)
            if best is None or e < best:
                best, best_shift = e, (dx, dy)
    cand["best_shift"] = best_shift
    r["alignment"] = cand
    return r


def save_pngs(p, m, out_dir, gain):
    h, w, _ = p.shape
    gap = np.full((h, 4, 3), 255, np.uint8)
    diff = p - m
    scale = gain / max(float(m.max()), 1e-12)
    # red: penumbra brighter, blue: Mitsuba brighter; full color at |diff| = max(m) / gain
    d = np.clip(luminance(diff) * scale, -1, 1)
    dimg = np.zeros_like(p)
    dimg[..., 0] = np.maximum(d, 0)
    dimg[..., 2] = np.maximum(-d, 0)
    dimg8 = np.round(dimg * 255).astype(np.uint8)
    side = np.concatenate([srgb8(p), gap, srgb8(m), gap, dimg8], axis=1)
    side_path = os.path.join(out_dir, "side_by_side.png")
    write_png(side_path, side)
    diff_path = os.path.join(out_dir, "diff.png")
    write_png(diff_path, dimg8)
    return side_path, diff_path


def write_pfm(path, img):
    h, w, _ = img.shape
    with open(path, "wb") as f:
        f.write(f"PF\n{w} {h}\n-1.0\n".encode())
        f.write(np.flipud(img).astype("<f4").tobytes())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--penumbra", default="target/release/penumbra", help="penumbra binary")
    ap.add_argument("--out", default=os.path.join(tempfile.gettempdir(), "mitsuba_compare"),
                    help="output folder (default: %(default)s)")
    ap.add_argument("--spp", type=int, default=1024, help="Mitsuba samples per pixel")
    ap.add_argument("--penumbra-spp", type=int, default=16,
                    help="penumbra grid samples per pixel (a perfect square)")
    ap.add_argument("--light-samples", type=int, default=None,
                    help="penumbra area light N (N*N samples; default from SCENE: 32)")
    ap.add_argument("--format", choices=["pfm", "exr"], default="exr",
                    help="penumbra output format (exr needs `pip install openexr`; "
                         "falls back to pfm when it is not installed)")
    ap.add_argument("--seed", type=int, default=0, help="Mitsuba sampler seed")
    ap.add_argument("--scale", type=float, default=1.0,
                    help="multiply both renderers' resolution by this factor")
    ap.add_argument("--gain", type=float, default=10.0,
                    help="diff.png saturates at |diff| = max(mitsuba) / gain")
    # Thresholds tuned for the defaults (256x192, 1024 spp): a correct penumbra gives about
    # 62 dB and 0.6 % mean relative difference; a sign error in one rotation angle gives
    # 45 dB and 2.6 %, a 1-degree fov error 44 dB and 4 %. Fewer spp means more Mitsuba noise.
    ap.add_argument("--ratio-tol", type=float, default=0.02)
    ap.add_argument("--min-psnr", type=float, default=50.0)
    ap.add_argument("--max-rel", type=float, default=0.015,
                    help="largest accepted mean relative difference over lit pixels")
    args = ap.parse_args()

    sc = dict(SCENE)
    sc["width"] = max(1, round(SCENE["width"] * args.scale))
    sc["height"] = max(1, round(SCENE["height"] * args.scale))
    if args.light_samples is not None:
        sc["light"] = dict(SCENE["light"], samples=args.light_samples)
    fmt = args.format
    if fmt == "exr":
        try:
            import OpenEXR  # noqa: F401
        except ImportError:
            print("note: OpenEXR not installed, using PFM", file=sys.stderr)
            fmt = "pfm"
    os.makedirs(args.out, exist_ok=True)

    p, tp, scene_path = render_penumbra(os.path.abspath(args.penumbra), sc, args.penumbra_spp,
                                        args.out, fmt)
    m, tm = render_mitsuba(sc, args.spp, args.seed)
    write_pfm(os.path.join(args.out, "mitsuba.pfm"), m)
    if p.shape != m.shape:
        print(f"FAIL: shapes differ: penumbra {p.shape}, mitsuba {m.shape}")
        return 1

    r = compare(p, m)
    side_path, diff_path = save_pngs(p, m, args.out, args.gain)
    a = r["alignment"]
    print(f"scene            {scene_path}")
    print(f"resolution       {sc['width']}x{sc['height']}, penumbra {args.penumbra_spp} spp grid + "
          f"{sc['light']['samples']}^2 light samples ({tp:.1f} s, {fmt}); "
          f"mitsuba direct {args.spp} spp ({tm:.1f} s)")
    print(f"max radiance     penumbra {p.max():.4f}  mitsuba {m.max():.4f}")
    print(f"PSNR             {r['psnr_clip']:.2f} dB (linear, clipped to [0,1]); "
          f"{r['psnr_norm']:.2f} dB (normalized by mitsuba max)")
    print("mean ratio       penumbra/mitsuba  R {:.4f}  G {:.4f}  B {:.4f}  (whole image)".format(
        *r["ratio"]))
    print("lit ratio        penumbra/mitsuba  R {:.4f}  G {:.4f}  B {:.4f}  "
          "(lit pixels, {:.0%} of image)".format(*r["ratio_lit"], r["lit_fraction"]))
    print(f"rel. difference  mean {r['mean_rel_lit']:.4f}, median {r['median_rel_lit']:.4f} "
          "(|Y_p - Y_m| / Y_m over lit pixels)")
    print(f"alignment MSE    identity {a['identity']:.3e}  flip_x {a['flip_x']:.3e}  "
          f"flip_y {a['flip_y']:.3e}  best integer shift (dx, dy) = {a['best_shift']}")
    print(f"images           {side_path} (penumbra | mitsuba | diff), {diff_path}")
    print(f"                 diff: red = penumbra brighter, blue = mitsuba brighter, "
          f"saturating at {100 / args.gain:.0f}% of the max")

    fails = []
    for name, v in zip("RGB", r["ratio"]):
        if abs(v - 1) > args.ratio_tol:
            fails.append(f"mean ratio {name} = {v:.4f}")
    if r["psnr_clip"] < args.min_psnr:
        fails.append(f"PSNR {r['psnr_clip']:.2f} dB < {args.min_psnr}")
    if r["mean_rel_lit"] > args.max_rel:
        fails.append(f"mean relative difference {r['mean_rel_lit']:.4f} > {args.max_rel}")
    if a["best_shift"] != (0, 0) or a["identity"] > min(a["flip_x"], a["flip_y"]):
        fails.append("images are not aligned")
    if fails:
        print("FAIL: " + "; ".join(fails))
        return 1
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
