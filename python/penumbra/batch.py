"""The batch command line: render the views a jobs file names on a Ray cluster.

    python -m penumbra.batch JOBS.toml [--address local|auto|HOST:PORT] [--num-cpus N]
                             [--cpus-per-task N] [--force] [--json] [--quiet]

A jobs file (TOML; relative paths are relative to its folder)::

    scene = "cornell.toml"               # the scene file
    output = "out/{name}.png"            # one image per view: {name} and {index}
    cpus_per_task = 1                    # optional: CPUs (threads) per view
    views_file = "poses.json"            # optional: a JSON list of views

    [defaults]                           # optional: settings of every view
    spp = 4
    width = 256
    height = 256

    [[views]]                            # views: a camera of the scene ...
    name = "front"
    camera = "front"

    [[views]]                            # ... or an explicit pinhole camera
    name = "corner"
    position = [0.9, 1.7, 2.5]
    look_at = [0, 1, 0]
    fov = 50

    [orbit]                              # optional: a turntable (see penumbra.views.orbit)
    center = [0, 1, 0]
    radius = 3
    frames = 24
    height = 0.5

Views whose image exists already are skipped (``--force`` renders them again). Progress goes
to stderr; the summary (one line per view, or JSON with ``--json``) to stdout. Exit status: 0
done, 1 a runtime failure (cluster unreachable, a task failed, a file not written), 2 a mistake
in the jobs file or the scene, 130 interrupted.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from typing import Any, Dict, List, Optional, Sequence

try:
    import tomllib
except ImportError:  # Python < 3.11
    import tomli as tomllib  # type: ignore[no-redef]

JOB_KEYS = ("scene", "output", "cpus_per_task", "views_file", "defaults", "views", "orbit")


class JobsError(ValueError):
    """A mistake in the jobs file."""


def read_jobs(path: str) -> Dict[str, Any]:
    """The jobs file at ``path``, with its paths resolved against its folder and its views
    expanded (``views``, then ``views_file``'s, then the orbit's). Raises :class:`JobsError`
    naming the file and key."""
    from . import views as v

    try:
        with open(path, "rb") as f:
            jobs = tomllib.load(f)
    except tomllib.TOMLDecodeError as e:
        raise JobsError(f"{path}: {e}") from None
    unknown = sorted(set(jobs) - set(JOB_KEYS))
    if unknown:
        raise JobsError(f"{path}: unknown key {unknown[0]!r} (known: {', '.join(JOB_KEYS)})")
    base = os.path.dirname(os.path.abspath(path))
    if "scene" not in jobs:
        raise JobsError(f"{path}: missing key 'scene' (the scene file to render)")
    specs: List[Any] = list(jobs.get("views", []))
    if "views_file" in jobs:
        try:
            specs += v.from_json(os.path.join(base, jobs["views_file"]))
        except (OSError, ValueError) as e:
            raise JobsError(f"{path}: views_file: {e}") from None
    if "orbit" in jobs:
        try:
            specs += v.orbit(**jobs["orbit"])
        except (TypeError, ValueError) as e:
            raise JobsError(f"{path}: orbit: {e}") from None
    if not specs:
        raise JobsError(f"{path}: no views (give [[views]], views_file or [orbit])")
    defaults = jobs.get("defaults", {})
    try:
        views = v.views(specs, **defaults)
    except (TypeError, ValueError) as e:
        raise JobsError(f"{path}: {e}") from None
    return {
        "scene": os.path.normpath(os.path.join(base, jobs["scene"])),
        "output": os.path.normpath(os.path.join(base, jobs.get("output", "out/{name}.png"))),
        "cpus_per_task": jobs.get("cpus_per_task", 1),
        "views": views,
    }


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Runs the command line with ``argv`` (default: ``sys.argv[1:]``); returns the exit
    status."""
    parser = argparse.ArgumentParser(
        prog="python -m penumbra.batch",
        description="Render the views of a jobs file on a Ray cluster.",
    )
    parser.add_argument("jobs", help="the jobs file (TOML)")
    parser.add_argument(
        "--address",
        default="local",
        help="local (a private Ray instance on this machine, the default), auto (the cluster "
        "this machine is part of) or HOST:PORT (a cluster's head)",
    )
    parser.add_argument("--num-cpus", type=int, help="CPUs of a local instance (default: all)")
    parser.add_argument("--cpus-per-task", type=float, help="CPUs (threads) per view")
    parser.add_argument("--force", action="store_true", help="render views whose image exists")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)

    try:
        import penumbra
        from penumbra import distributed
    except ImportError as e:
        print(f"penumbra.batch: {e} (install Ray with `pip install .[ray]`)", file=sys.stderr)
        return 1
    try:
        jobs = read_jobs(args.jobs)
        scene = penumbra.load(jobs["scene"])
    except FileNotFoundError as e:
        print(f"penumbra.batch: {e.filename}: {e.strerror}", file=sys.stderr)
        return 2
    except ValueError as e:  # JobsError and penumbra.SceneError
        print(f"penumbra.batch: {e}", file=sys.stderr)
        return 2
    try:
        distributed.connect(args.address, num_cpus=args.num_cpus)
        summary = distributed.render_views(
            scene,
            jobs["views"],
            output=jobs["output"],
            num_cpus=args.cpus_per_task or jobs["cpus_per_task"],
            force=args.force,
            progress=not args.quiet and sys.stderr.isatty() or None,
        )
    except KeyboardInterrupt:
        print("penumbra.batch: interrupted", file=sys.stderr)
        return 130
    except ValueError as e:
        print(f"penumbra.batch: {e}", file=sys.stderr)
        return 2
    except Exception as e:  # the cluster, a task or a write failed
        print(f"penumbra.batch: {type(e).__name__}: {e}", file=sys.stderr)
        return 1
    finally:
        if args.address == "local":
            import ray

            ray.shutdown()
    if args.json:
        json.dump({"views": summary}, sys.stdout, indent=1)
        print()
    else:
        for r in summary:
            how = (
                "skipped (exists)"
                if r["skipped"]
                else f"{r['seconds']:.2f} s, {r['rays_per_second'] / 1e6:.1f} Mrays/s"
            )
            print(f"{r['name']}\t{r['path']}\t{how}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
