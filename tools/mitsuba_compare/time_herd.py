#!/usr/bin/env python3
"""Time Mitsuba 3 and penumbra on an instanced scene (scenes/herd.toml), turn by turn.

The herd is 400 placements of Spot the cow (5,856 triangles each, 2.3 M in all) on a textured
ground under one area light: penumbra builds the cow's tree once and places it 400 times (the
copies would hold more than 2^20 triangles), Mitsuba gets one `shapegroup` per material and
one `instance` per placement with the same object-to-world matrix (the placement's
T·Rz·Ry·Rx·S, then the entry's own transform). Both use the physical light model with direct
lighting only: penumbra with `light_model = "physical"`, no ambient term and a black
background (set on its command line); Mitsuba's `direct` integrator with `emitter_samples`
N×N and no BSDF samples, the emitter hidden. Textures are translated too (the cow's image as a
`bitmap`, the ground's checker as a `checkerboard`), so the two images should agree up to
noise and texture filtering; the PSNR between them is printed as a check of the translation.

Both report render time only (Mitsuba: `mi.render` plus evaluation, after one untimed render
that compiles its kernels; penumbra: `render_seconds` of its `--json` summary, which leaves
out loading and the tree's build, reported beside it). Needs `mitsuba` from PyPI, so CI does
not run it.

    python3 tools/mitsuba_compare/time_herd.py --penumbra target/release/penumbra
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import compare  # noqa: E402  (the Mitsuba translation helpers)

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
HERD = os.path.join(ROOT, "scenes", "herd.toml")


def placement(t):
    """p' = T·Rz·Ry·Rx·S·p of a `{ translate, rotate, scale }` table (or its `matrix`)."""
    if "matrix" in t:
        return np.asarray(t["matrix"], dtype=np.float64)
    rx, ry, rz = t.get("rotate", [0, 0, 0])
    s = t.get("scale", [1, 1, 1])
    s = s if isinstance(s, list) else [s] * 3
    lin = compare.rot_z(rz) @ compare.rot_y(ry) @ compare.rot_x(rx) @ np.diag(s)
    return compare.affine(lin, compare.vec(t.get("translate", [0, 0, 0])))


def mitsuba_scene(mi, herd, spp, light_n, scale):
    T = mi.ScalarTransform4f
    base = os.path.dirname(HERD)
    textures = herd["textures"]

    def reflectance(material):
        m = herd["materials"][material]
        kd = m["diffuse"] if isinstance(m["diffuse"], list) else [m["diffuse"]] * 3
        tex = textures.get(m.get("texture"))
        if tex is None:
            return {"type": "rgb", "value": kd}
        if tex["type"] == "image":
            return {"type": "bitmap", "filename": os.path.join(base, tex["file"])}
        # penumbra's checker: `checks` squares a side over [0, 1]²; Mitsuba's has 2×2 over
        # its unit, starting with color0 (penumbra's `even`).
        return {"type": "checkerboard", "color0": {"type": "rgb", "value": tex["even"]},
                "color1": {"type": "rgb", "value": tex["odd"]},
                "to_uv": T().scale([tex["checks"] / 2, tex["checks"] / 2, 1])}

    def bsdf(material):
        return {"type": "twosided",
                "material": {"type": "diffuse", "reflectance": reflectance(material)}}

    cam = herd["camera"]
    film = herd["film"]
    d = {
        "type": "scene",
        "integrator": {"type": "direct", "hide_emitters": True,
                       "emitter_samples": light_n ** 2, "bsdf_samples": 0},
        "sensor": compare.sensor(mi, cam, round(film["width"] * scale),
                                 round(film["height"] * scale), spp),
    }
    light = herd["lights"][0]
    d["light"] = {
        "type": "rectangle",
        "to_world": T(compare.parallelogram_to_world(light["center"], light["u"],
                                                     light["v"]).tolist()),
        "emitter": {"type": "area", "radiance": {
            "type": "rgb", "value": (compare.vec(light["color"]) * light["intensity"]).tolist()}},
        "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}},
    }
    for i, o in enumerate(herd["objects"]):
        if o["type"] == "quad":
            c = compare.vec(o["corner"]) + compare.vec(o["u"]) / 2 + compare.vec(o["v"]) / 2
            m = compare.parallelogram_to_world(c, o["u"], o["v"])
            d[f"quad{i}"] = {"type": "rectangle", "to_world": T(m.tolist()),
                             "bsdf": bsdf(o["material"])}
            continue
        assert o["type"] == "instances", o["type"]
        outer = placement(o)
        groups = {}
        for k, t in enumerate(o["transforms"]):
            material = t.get("material", o["material"])
            if material not in groups:
                groups[material] = f"group{i}_{material}"
                d[groups[material]] = {"type": "shapegroup", "mesh": {
                    "type": "obj", "filename": os.path.join(base, o["file"]),
                    "bsdf": bsdf(material)}}
            d[f"instance{i}_{k}"] = {"type": "instance",
                                     "shapegroup": {"type": "ref", "id": groups[material]},
                                     "to_world": T((outer @ placement(t)).tolist())}
    return d


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--penumbra", required=True, help="path to the penumbra binary")
    ap.add_argument("--scale", type=float, default=2.0, help="resolution factor (640×360 × it)")
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--light-samples", type=int, default=4, help="N: N×N light samples")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--threads", type=int, default=0, help="penumbra threads (0: all)")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    args = ap.parse_args()

    import drjit as dr
    import mitsuba as mi

    mi.set_variant(args.variant)
    with open(HERD, "rb") as f:
        herd = tomllib.load(f)
    scene = mi.load_dict(mitsuba_scene(mi, herd, args.spp, args.light_samples, args.scale))
    mitsuba_img = np.array(mi.render(scene, spp=args.spp, seed=0))[..., :3]  # compiles

    width = round(herd["film"]["width"] * args.scale)
    height = round(herd["film"]["height"] * args.scale)
    sets = {"render.light_model": '"physical"', "render.ambient": "0",
            "render.background": "0", "render.samples": str(args.spp),
            "render.light_samples": str(args.light_samples), "film.width": str(width),
            "film.height": str(height)}
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "p.pfm")
        cmd = [args.penumbra, "render", HERD, "-o", out, "--json", "--quiet",
               "--allow-path", os.path.join(ROOT, "assets")]  # the herd reads ../assets
        cmd += [a for k, v in sets.items() for a in ("--set", f"{k}={v}")]
        if args.threads:
            cmd += ["--threads", str(args.threads)]
        mitsuba_s, penumbra_s, setup_s = [], [], []
        for run in range(args.runs):
            t0 = time.perf_counter()
            dr.eval(mi.render(scene, spp=args.spp, seed=run + 1))
            mitsuba_s.append(time.perf_counter() - t0)
            summary = json.loads(subprocess.run(cmd, check=True, capture_output=True,
                                                text=True).stdout)
            penumbra_s.append(summary["render_seconds"])
            setup_s.append(summary["load_seconds"] + summary["bvh_build_seconds"])
        penumbra_img = compare.read_pfm(out)
    print(json.dumps({
        "scene": "herd", "width": width, "height": height, "spp": args.spp,
        "light_samples": args.light_samples ** 2, "triangles": summary["triangles"],
        "mitsuba_variant": args.variant,
        "mitsuba_render_s_median": round(statistics.median(mitsuba_s), 4),
        "penumbra_render_s_median": round(statistics.median(penumbra_s), 4),
        "penumbra_load_and_build_s_median": round(statistics.median(setup_s), 4),
        "ratio_penumbra_over_mitsuba": round(statistics.median(penumbra_s)
                                             / statistics.median(mitsuba_s), 3),
        "psnr_db": round(compare.psnr(np.clip(penumbra_img, 0, 1),
                                      np.clip(mitsuba_img, 0, 1)), 1),
        "loadavg": open("/proc/loadavg").read().split()[:3],
    }))


if __name__ == "__main__":
    main()
