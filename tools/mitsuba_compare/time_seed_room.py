#!/usr/bin/env python3
"""Time Mitsuba 3 and penumbra on the seed's room (scenes/cornell.toml), turn by turn.

Mitsuba renders with its LLVM variant: the `direct` integrator, `emitter_samples` light samples
and no BSDF samples per camera sample, diffuse materials only. penumbra renders the same room
with `light_model = "physical"` and the same sample counts (rgss spp, N×N light samples).
Both report render time only (Mitsuba: `mi.render` plus evaluation, after one untimed render
that compiles its kernels; penumbra: `render_seconds` of its `--json` summary). Needs `mitsuba`
from PyPI, so CI does not run it.

With `--environment FILE`, the room's area light is replaced by an environment light of that
map (penumbra `type = "environment"`, `samples` N; Mitsuba `envmap`), hidden from the camera in
both, and the room's open front lets it in.

    python3 tools/mitsuba_compare/time_seed_room.py --penumbra target/release/penumbra
    python3 tools/mitsuba_compare/time_seed_room.py --penumbra target/release/penumbra \
        --environment ../shared/assets/hdri/studio_small_03_1k.hdr --light-samples 8
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

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import compare  # noqa: E402  (the Mitsuba scene translation)

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")


def seed_room(size, light_n):
    """The seed room as compare.py's scene dictionary (front camera, diffuse colors)."""
    with open(os.path.join(ROOT, "scenes", "cornell.toml"), "rb") as f:
        t = tomllib.load(f)
    grey = lambda c: c if isinstance(c, list) else [c] * 3  # noqa: E731
    cam = t["cameras"]["front"]
    light = t["lights"][0]
    return {
        "width": size, "height": size,
        "camera": {k: cam[k] for k in ("position", "look_at", "up", "fov")},
        "materials": {k: grey(v["diffuse"]) for k, v in t["materials"].items()},
        "quads": [o for o in t["objects"] if o["type"] == "quad"],
        "cubes": [dict(o, size=grey(o["size"]), rotate=o.get("rotate", [0, 0, 0]))
                  for o in t["objects"] if o["type"] == "cube"],
        "light": {k: light[k] for k in ("center", "u", "v", "color", "intensity")}
        | {"samples": light_n},
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--penumbra", required=True, help="path to the penumbra binary")
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--light-samples", type=int, default=5, help="N: N×N light samples")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--environment", help="light the room with this map instead")
    args = ap.parse_args()

    import drjit as dr
    import mitsuba as mi

    mi.set_variant(args.variant)
    sc = seed_room(args.size, args.light_samples)
    d = compare.mitsuba_scene(mi, sc, args.spp)
    d["integrator"] = {"type": "direct", "hide_emitters": True,
                       "emitter_samples": args.light_samples ** 2, "bsdf_samples": 0}
    toml = compare.penumbra_toml(sc, args.spp).replace('sampler = "grid"', 'sampler = "rgss"')
    if args.environment:
        env = os.path.abspath(args.environment)
        del d["light"]
        d["env"] = {"type": "envmap", "filename": env}
        area = toml.index("[[lights]]")
        toml = (toml[:area] + f'[[lights]]\ntype = "environment"\nfile = {json.dumps(env)}\n'
                f"samples = {args.light_samples}\nvisible = false\n\n"
                + toml[toml.index("[[objects]]", area):])
    scene = mi.load_dict(d)
    dr.eval(mi.render(scene, spp=args.spp, seed=0))  # compiles the kernels

    with tempfile.TemporaryDirectory() as tmp:
        toml_path = os.path.join(tmp, "seed_room.toml")
        with open(toml_path, "w") as f:
            f.write(toml)
        out = os.path.join(tmp, "p.pfm")
        mitsuba_s, penumbra_s = [], []
        for run in range(args.runs):
            t0 = time.perf_counter()
            dr.eval(mi.render(scene, spp=args.spp, seed=run + 1))
            mitsuba_s.append(time.perf_counter() - t0)
            summary = subprocess.run([args.penumbra, "render", toml_path, "-o", out, "--json",
                                      "--quiet"], check=True, capture_output=True, text=True)
            penumbra_s.append(json.loads(summary.stdout)["render_seconds"])
    print(json.dumps({
        "size": args.size, "spp": args.spp, "light_samples": args.light_samples ** 2,
        "mitsuba_variant": args.variant, "light": args.environment or "area",
        "mitsuba_render_s_median": round(statistics.median(mitsuba_s), 4),
        "penumbra_render_s_median": round(statistics.median(penumbra_s), 4),
        "ratio_penumbra_over_mitsuba": round(statistics.median(penumbra_s)
                                             / statistics.median(mitsuba_s), 3),
        "loadavg": open("/proc/loadavg").read().split()[:3],
    }))


if __name__ == "__main__":
    main()
