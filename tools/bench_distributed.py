#!/usr/bin/env python3
"""Distributed rendering benchmark (not a test): penumbra.distributed on a local Ray instance
against one process, alternately in the same run, on the seed's room (scenes/cornell.toml).

    python tools/bench_distributed.py [--cpus 2] [--repeat 3] [--frame-size 1024]
                                      [--frame-spp 36] [--views 64] [--view-size 256]

(a) Frame: ``scene.render(threads=CPUS)`` in this process against
    ``distributed.render_frame(scene)`` with 4 tiles per CPU, each task on 1 CPU, and with
    ``num_cpus=CPUS`` (a whole node per task) (the workers' worlds built beforehand: cluster
    start-up excluded).
(b) Views: VIEWS orbit views rendered (and written) one after another by
    ``scene.render(threads=1)`` and by ``scene.render(threads=CPUS)``, against ``distributed.render_views`` (one task per view, 1 CPU each, and a whole node
    each): throughput ratio.
(c) Task overhead: VIEWS views of 1×1 pixel through ``render_views``, per view.
Prints medians of --repeat runs and their ratios on stdout; progress on stderr. Needs Ray
(``pip install .[ray]``); build the package with the release profile for meaningful figures
(``PENUMBRA_PY_PROFILE=release tools/test.sh -k nothing`` or ``pip install .``).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

for key, value in {
    "RAY_USAGE_STATS_ENABLED": "0",
    "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0",
    "RAY_AUTH_MODE": "disabled",
}.items():
    os.environ.setdefault(key, value)

import ray  # noqa: E402

import penumbra  # noqa: E402
from penumbra import distributed, views  # noqa: E402

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "cornell.toml"


def timed(f):
    start = time.perf_counter()
    f()
    return time.perf_counter() - start


def one_process(scene, orbit, pattern, threads, size) -> None:
    """The batch in this process, one view after another, each written as render_views does."""
    for v in orbit:
        image = scene.render(camera=v["camera"], threads=threads, **size)
        penumbra.write_image(pattern.format(name=v["name"]), image)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cpus", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--frame-size", type=int, default=1024)
    ap.add_argument("--frame-spp", type=int, default=36)
    ap.add_argument("--views", type=int, default=64)
    ap.add_argument("--view-size", type=int, default=256)
    args = ap.parse_args()

    scene = penumbra.load(SCENE)
    start = time.perf_counter()
    ray.init(num_cpus=args.cpus, include_dashboard=False, log_to_driver=False)
    print(f"ray.init: {time.perf_counter() - start:.2f} s", file=sys.stderr)
    orbit = views.orbit(center=(0, 1, -3), radius=2.6, height=4.2, frames=args.views, fov=75)
    frame = dict(width=args.frame_size, height=args.frame_size, spp=args.frame_spp)
    size = dict(width=args.view_size, height=args.view_size)
    # Warm up: every worker builds the world once (and imports penumbra).
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        distributed.render_views(
            scene, orbit, output=f"{tmp}/warm-{{name}}.png", width=1, height=1, force=True
        )
        print(f"warm-up (world builds): {time.perf_counter() - start:.2f} s", file=sys.stderr)

        rows: dict = {
            "frame, one process": [],
            "frame, Ray tiles": [],
            "frame, Ray node tasks": [],
            "views, one thread": [],
            "views, one process": [],
            "views, Ray": [],
            "views, Ray node tasks": [],
            "1x1 views, Ray": [],
        }
        for r in range(args.repeat):
            print(f"round {r + 1}/{args.repeat}", file=sys.stderr)
            rows["frame, one process"].append(
                timed(lambda: scene.render(threads=args.cpus, **frame))
            )
            rows["frame, Ray tiles"].append(timed(lambda: distributed.render_frame(scene, **frame)))
            rows["frame, Ray node tasks"].append(
                timed(lambda: distributed.render_frame(scene, num_cpus=args.cpus, **frame))
            )
            # The single-process batch writes its images too, as render_views does.
            rows["views, one thread"].append(
                timed(lambda: one_process(scene, orbit, f"{tmp}/one-{{name}}.exr", 1, size))
            )
            rows["views, one process"].append(
                timed(lambda: one_process(scene, orbit, f"{tmp}/one-{{name}}.exr", args.cpus, size))
            )
            rows["views, Ray"].append(
                timed(
                    lambda: distributed.render_views(
                        scene, orbit, output=f"{tmp}/{{name}}.exr", force=True, **size
                    )
                )
            )
            rows["views, Ray node tasks"].append(
                timed(
                    lambda: distributed.render_views(
                        scene,
                        orbit,
                        output=f"{tmp}/{{name}}.exr",
                        force=True,
                        num_cpus=args.cpus,
                        **size,
                    )
                )
            )
            rows["1x1 views, Ray"].append(
                timed(
                    lambda: distributed.render_views(
                        scene,
                        orbit,
                        output=f"{tmp}/tiny-{{name}}.pfm",
                        force=True,
                        width=1,
                        height=1,
                    )
                )
            )
    ray.shutdown()

    med = {k: statistics.median(v) for k, v in rows.items()}
    print(f"{'workload':<22} {'median s':>9}  runs")
    for k, v in rows.items():
        print(f"{k:<22} {med[k]:9.3f}  {' '.join(f'{x:.3f}' for x in v)}")
    print(
        f"frame: Ray / one process = {med['frame, Ray tiles'] / med['frame, one process']:.3f}x (target <= 1.15)"
    )
    print(
        f"frame: Ray, node tasks / one process = {med['frame, Ray node tasks'] / med['frame, one process']:.3f}x"
    )
    print(
        f"views: throughput Ray / one thread = {med['views, one thread'] / med['views, Ray']:.2f}x (target >= 1.8)"
    )
    one = med["views, one process"]
    print(
        f"views: one process, {args.cpus} threads / one thread = {med['views, one thread'] / one:.2f}x"
    )
    print(
        f"views: throughput Ray / one process of {args.cpus} threads = {one / med['views, Ray']:.2f}x"
    )
    print(
        f"views: throughput Ray, node tasks / one thread = {med['views, one thread'] / med['views, Ray node tasks']:.2f}x"
    )
    print(
        f"task overhead: {1000 * med['1x1 views, Ray'] / len(orbit):.1f} ms per view (1x1 pixel, image written)"
    )


if __name__ == "__main__":
    main()
