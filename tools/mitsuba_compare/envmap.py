#!/usr/bin/env python3
"""Environment and directional lights against Mitsuba 3: diffuse boxes on a ground plane lit
by an HDR map, or by a sun.

For each map and rotation, renders the same scene with penumbra (`light_model = "physical"`,
an `environment` light, visible) and with Mitsuba 3 (`envmap` emitter with
`to_world = rotate([0, 1, 0], rotation)`, `direct` integrator, emitters visible), and compares
the 8-bit sRGB images (PSNR) and the mean linear brightness. The map is visible in the upper
part of the frame, so a flipped or turned map shows in the background as well as in the
lighting. Manual validation like `compare.py` (CI does not run it: it needs Mitsuba and takes
minutes). See README.md in this folder.

    python3 tools/mitsuba_compare/envmap.py --penumbra target/release/penumbra \
        --maps ../shared/assets/hdri/venice_sunset_1k.hdr --rotations 0 90
    python3 tools/mitsuba_compare/envmap.py --sun 3 -1 -2 -1.5   # irradiance, direction

With `--sun E DX DY DZ`, the light is a penumbra `directional` light of irradiance E travelling
along (DX, DY, DZ) against Mitsuba's `directional` emitter with the same `irradiance` and
`direction` (no map, black background).
"""

import argparse
import json
import math
import os
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from compare import (  # noqa: E402
    cube_to_world,
    parallelogram_to_world,
    psnr,
    read_pfm,
    sensor,
    srgb8,
    toml_vec,
    vec,
    write_png,
)

SCENE = {
    "width": 192,
    "height": 128,
    "camera": {"position": [0.0, 2.2, 7.5], "look_at": [0.0, 1.2, 0.0], "up": [0.0, 1.0, 0.0],
               "fov": 45.0},
    "materials": {"floor": [0.6, 0.6, 0.6], "box": [0.8, 0.35, 0.15],
                  "tilted": [0.3, 0.75, 0.3]},
    # u x v = x x z = -y: the floor faces down (both renderers shade both sides).
    "quads": [{"material": "floor", "corner": [-4.0, 0.0, -4.0], "u": [8.0, 0.0, 0.0],
               "v": [0.0, 0.0, 8.0]}],
    "cubes": [
        {"material": "box", "center": [-1.0, 0.75, 0.3], "size": [1.5, 1.5, 1.5],
         "rotate": [0.0, 30.0, 0.0]},
        {"material": "tilted", "center": [1.4, 1.0, -0.8], "size": [1.2, 0.5, 0.9],
         "rotate": [25.0, 40.0, 15.0]},
    ],
}


def light_toml(env, rotation, n, sun):
    if sun:
        e, *d = sun
        return ["[[lights]]", 'type = "directional"', f"direction = {toml_vec(d)}",
                f"intensity = {float(e)!r}", ""]
    return ["[[lights]]", 'type = "environment"', f"file = {json.dumps(os.path.abspath(env))}",
            f"rotation = {float(rotation)!r}", f"samples = {n}", ""]


def penumbra_toml(sc, env, rotation, spp, n, sun=None):
    cam = sc["camera"]
    lines = [
        "[film]", f"width = {sc['width']}", f"height = {sc['height']}", "",
        "[camera]", f"position = {toml_vec(cam['position'])}",
        f"look_at = {toml_vec(cam['look_at'])}", f"up = {toml_vec(cam['up'])}",
        f"fov = {float(cam['fov'])!r}", "",
        "[render]", 'light_model = "physical"', 'sampler = "grid"', f"samples = {spp}",
        "ambient = 0", "",
    ] + light_toml(env, rotation, n, sun)
    for name, kd in sc["materials"].items():
        lines += [f"[materials.{name}]", f"diffuse = {toml_vec(kd)}", "specular = [0, 0, 0]", ""]
    for q in sc["quads"]:
        lines += ["[[objects]]", 'type = "quad"', f"material = \"{q['material']}\"",
                  f"corner = {toml_vec(q['corner'])}", f"u = {toml_vec(q['u'])}",
                  f"v = {toml_vec(q['v'])}", ""]
    for c in sc["cubes"]:
        lines += ["[[objects]]", 'type = "cube"', f"material = \"{c['material']}\"",
                  f"center = {toml_vec(c['center'])}", f"size = {toml_vec(c['size'])}",
                  f"rotate = {toml_vec(c['rotate'])}", ""]
    return "\n".join(lines)


def render_penumbra(exe, sc, env, rotation, spp, n, out_dir, sun=None):
    import subprocess

    scene = os.path.join(out_dir, "scene.toml")
    with open(scene, "w") as f:
        f.write(penumbra_toml(sc, env, rotation, spp, n, sun))
    img = os.path.join(out_dir, "penumbra.pfm")
    subprocess.run([exe, "render", scene, "-o", img, "--quiet"], check=True)
    return read_pfm(img)


def render_mitsuba(sc, env, rotation, spp, seed, sun=None):
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    T = mi.ScalarTransform4f
    cam = sc["camera"]

    def bsdf(kd):
        return {"type": "twosided", "material": {
            "type": "diffuse", "reflectance": {"type": "rgb", "value": list(map(float, kd))}}}

    d = {
        "type": "scene",
        "integrator": {"type": "direct", "hide_emitters": False},
        "sensor": sensor(mi, cam, sc["width"], sc["height"], spp),
    }
    if sun:
        e, *direction = sun
        d["sun"] = {"type": "directional", "direction": [float(x) for x in direction],
                    "irradiance": {"type": "rgb", "value": [float(e)] * 3}}
    else:
        d["env"] = {"type": "envmap", "filename": os.path.abspath(env),
                    "to_world": T().rotate(axis=[0, 1, 0], angle=float(rotation))}
    for i, q in enumerate(sc["quads"]):
        c = vec(q["corner"]) + vec(q["u"]) / 2 + vec(q["v"]) / 2
        d[f"quad{i}"] = {"type": "rectangle",
                         "to_world": T(parallelogram_to_world(c, q["u"], q["v"]).tolist()),
                         "bsdf": bsdf(sc["materials"][q["material"]])}
    for i, c in enumerate(sc["cubes"]):
        d[f"cube{i}"] = {"type": "cube", "to_world": T(cube_to_world(c).tolist()),
                         "bsdf": bsdf(sc["materials"][c["material"]])}
    scene = mi.load_dict(d)
    return np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float32)[..., :3]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--penumbra", default="target/release/penumbra")
    ap.add_argument("--maps", nargs="+", default=[])
    ap.add_argument("--sun", nargs=4, type=float, metavar=("E", "DX", "DY", "DZ"),
                    help="compare a directional light instead of maps")
    ap.add_argument("--rotations", nargs="+", type=float, default=[0.0, 90.0])
    ap.add_argument("--spp", type=int, default=16, help="penumbra pixel samples (a square)")
    ap.add_argument("--n", type=int, default=16, help="penumbra environment samples N (N×N)")
    ap.add_argument("--mitsuba-spp", type=int, default=1024)
    ap.add_argument("--min-psnr", type=float, default=40.0)
    ap.add_argument("--max-mean-error", type=float, default=0.01)
    ap.add_argument("--out", default=os.path.join(tempfile.gettempdir(), "mitsuba_envmap"))
    args = ap.parse_args()

    ok = True
    cases = [(env, rot) for env in args.maps for rot in args.rotations]
    if args.sun:
        cases = [(None, 0.0)]
    for env, rotation in cases:
        if True:
            name = "sun" if args.sun else \
                f"{os.path.splitext(os.path.basename(env))[0]}_rot{rotation:g}"
            out = os.path.join(args.out, name)
            os.makedirs(out, exist_ok=True)
            p = render_penumbra(args.penumbra, SCENE, env, rotation, args.spp, args.n, out,
                                args.sun)
            m = render_mitsuba(SCENE, env, rotation, args.mitsuba_spp, seed=1, sun=args.sun)
            p8, m8 = srgb8(p), srgb8(m)
            db = psnr(p8.astype(np.float64) / 255, m8.astype(np.float64) / 255)
            mean = float(p.mean() / m.mean()) - 1.0
            # A turned or flipped map: its best match is not the identity.
            flips = {"turned_180": psnr(srgb8(p)[:, ::-1] / 255.0, m8 / 255.0)}
            passed = db >= args.min_psnr and abs(mean) <= args.max_mean_error
            ok &= passed
            side = np.concatenate([p8, np.full((p8.shape[0], 4, 3), 255, np.uint8), m8], 1)
            write_png(os.path.join(out, "side_by_side.png"), side)
            print(f"{name}: PSNR {db:.1f} dB (8-bit sRGB), mean {mean * 100:+.2f} %, "
                  f"mirrored {flips['turned_180']:.1f} dB -> {'ok' if passed else 'FAIL'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
