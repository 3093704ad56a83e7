"""The batch command line: render the views a jobs file names on a Ray cluster.

    python -m penumbra.batch JOBS.toml [--address local|auto|HOST:PORT] [--num-cpus N]
                             [--cpus-per-task N] [--force] [--manifest FILE.jsonl]
                             [--no-meta] [--coco FILE.json] [--json] [--quiet]

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

Each image gets its record beside it (``out/a.png`` → ``out/a.meta.json``, as ``penumbra
render --meta`` writes it: see :mod:`penumbra.record`), and a view is skipped when its image
exists and its record says it was made with exactly the settings it would be rendered with
now (the scene's digest, penumbra's version, the camera, the render settings, the AOVs, the
gamma, the format): the rule of ``penumbra render --resume``. An interrupted batch, run
again, renders what is missing; another scene or other settings writing to the same files
render them all again. ``--force`` renders every view; ``--no-meta`` writes no records, so
that every view renders. With ``--manifest FILE.jsonl`` each view's line (task, camera, seed,
seconds, peak memory and host of its task, outputs, status) is appended to FILE as it ends, as
``penumbra render --manifest`` writes it. ``--coco FILE.json`` writes COCO annotations of
every view's ``object_id`` AOV at the end (see :mod:`penumbra.coco`; needs pycocotools).
Each view's line (name, image, time) is printed as soon as it is done, skipped views first,
so that an interrupted batch has told what it finished: on stdout, or with ``--json`` on
stderr while stdout gets the whole summary as one JSON object at the end. A mistake names its view (its
name, else its place) with its key path in the file (``views[3]``) and the line of its
``[[views]]`` table. Exit status: 0 done, 1 a runtime failure (cluster unreachable, a task
failed, a file not written), 2 a mistake in the jobs file or the scene, 130 interrupted.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import sys
from typing import Any, Dict, Iterable, Iterator, List, Optional, Sequence, TextIO, Tuple

try:
    import tomllib
except ImportError:  # Python < 3.11
    import tomli as tomllib  # type: ignore[no-redef]

#: The keys of a jobs file, with the type each value must have, as messages name it.
JOB_TYPES: Dict[str, Tuple[Any, str]] = {
    "scene": (str, "a file name"),
    "output": (str, "a file name pattern"),
    "cpus_per_task": ((int, float), "a number of CPUs"),
    "views_file": (str, "a file name"),
    "defaults": (dict, "a table ([defaults])"),
    "views": (list, "a list of tables ([[views]])"),
    "orbit": (dict, "a table ([orbit])"),
}
JOB_KEYS = tuple(JOB_TYPES)
#: The keys of ``[orbit]``: the arguments of :func:`penumbra.views.orbit`, and settings.
ORBIT_KEYS = ("center", "radius", "frames", "height", "fov", "up", "start_degrees", "name")


class JobsError(ValueError):
    """A mistake in the jobs file."""


def _table_lines(text: str, key: str) -> List[int]:
    """The 1-based line of each ``[[key]]`` table header of a TOML text, in order."""
    header = re.compile(r"\s*\[\[\s*" + re.escape(key) + r"\s*\]\]\s*(#.*)?$")
    return [n for n, line in enumerate(text.splitlines(), 1) if header.match(line)]


def _origins(
    jobs: Dict[str, Any], text: str, from_file: int, orbit: int
) -> List[Tuple[str, Optional[int]]]:
    """Where each view of the batch comes from: its key path in the jobs file (``views[i]``,
    ``views_file[i]``, ``orbit`` frame k) and its line, when known."""
    listed = len(jobs.get("views", []))
    lines: List[Optional[int]] = list(_table_lines(text, "views"))
    if len(lines) != listed:  # views written inline, or a header inside a string
        lines = [None] * listed
    out: List[Tuple[str, Optional[int]]] = [(f"views[{i}]", lines[i]) for i in range(listed)]
    out += [(f"views_file[{i}]", None) for i in range(from_file)]
    out += [(f"[orbit] frame {k}", None) for k in range(orbit)]
    return out


def describe(
    path: str, origin: Tuple[str, Optional[int]], index: int, name: Optional[str]
) -> str:
    """A view of the jobs file at ``path`` as a message names it: ``FILE:LINE: view NAME
    (KEY)``, with its 1-based place in the batch instead of a name when it has none."""
    key, line = origin
    where = f"{path}:{line}" if line is not None else path
    who = f"view {name!r}" if name else f"view {index + 1}"
    return f"{where}: {who} ({key})"


def _check_keys(path: str, jobs: Dict[str, Any]) -> None:
    """Raises :class:`JobsError` for an unknown key anywhere outside ``[[views]]`` (whose
    views :func:`penumbra.views.view` checks), a value of the wrong type, or no scene."""

    def unknown(table: str, keys: Iterable[str], known: Sequence[str]) -> None:
        extra = sorted(set(keys) - set(known))
        if extra:
            raise JobsError(
                f"{path}: {table}unknown key {extra[0]!r} (known: {', '.join(known)})"
            )

    unknown("", jobs, JOB_KEYS)
    if "scene" not in jobs:
        raise JobsError(f"{path}: missing key 'scene' (the scene file to render)")
    for key, value in jobs.items():
        kind, what = JOB_TYPES[key]
        if not isinstance(value, kind) or isinstance(value, bool):
            raise JobsError(f"{path}: {key} must be {what}, not {value!r}")
    cpus = jobs.get("cpus_per_task", 1)
    if not 0 < cpus < float("inf"):
        raise JobsError(f"{path}: cpus_per_task must be a positive number of CPUs, not {cpus!r}")
    from .views import SETTING_KEYS, setting_problem

    defaults = jobs.get("defaults", {})
    unknown("[defaults]: ", defaults, SETTING_KEYS)
    for key, value in defaults.items():
        problem = setting_problem(key, value)
        if problem:
            raise JobsError(f"{path}: [defaults]: {problem}")
    unknown("[orbit]: ", jobs.get("orbit", {}), ORBIT_KEYS + SETTING_KEYS)


def read_jobs(path: str) -> Dict[str, Any]:
    """The jobs file at ``path``, with its paths resolved against its folder and its views
    expanded (``views``, then ``views_file``'s, then the orbit's). Raises :class:`JobsError`
    naming the file, and for a mistake in a view the view, its key path and line. The result
    has ``scene``, ``output``, ``cpus_per_task``, ``views`` (normalized) and ``origins``
    (where each view is in the file: its key path and line, or None)."""
    from . import views as v

    try:
        with open(path, "rb") as f:
            raw = f.read()
        text = raw.decode("utf-8")
        jobs = tomllib.loads(text)
    except UnicodeDecodeError as e:
        raise JobsError(f"{path}: not UTF-8 text: {e}") from None
    except tomllib.TOMLDecodeError as e:  # its message has the line and column
        raise JobsError(f"{path}: {e}") from None
    _check_keys(path, jobs)
    base = os.path.dirname(os.path.abspath(path))
    specs: List[Any] = list(jobs.get("views", []))
    from_file: List[Any] = []
    if "views_file" in jobs:
        try:
            from_file = v.from_json(os.path.join(base, jobs["views_file"]))
        except (OSError, ValueError) as e:
            raise JobsError(f"{path}: views_file: {e}") from None
    orbit: List[Any] = []
    if "orbit" in jobs:
        try:
            orbit = v.orbit(**jobs["orbit"])
        except (TypeError, ValueError) as e:
            raise JobsError(f"{path}: {e}") from None  # "orbit: radius must be ..."
    specs += from_file + orbit
    if not specs:
        raise JobsError(f"{path}: no views (give [[views]], views_file or [orbit])")
    origins = _origins(jobs, text, len(from_file), len(orbit))
    defaults = jobs.get("defaults", {})
    try:
        views = v.views(specs, **defaults)
    except v.ViewError as e:
        where = describe(path, origins[e.index], e.index, e.name)
        raise JobsError(f"{where}: {e.reason}") from None
    except (TypeError, ValueError) as e:
        raise JobsError(f"{path}: {e}") from None
    return {
        "scene": os.path.normpath(os.path.join(base, jobs["scene"])),
        "output": os.path.normpath(os.path.join(base, jobs.get("output", "out/{name}.png"))),
        "cpus_per_task": jobs.get("cpus_per_task", 1),
        "views": views,
        "origins": origins,
    }


def check_views(path: str, jobs: Dict[str, Any], scene: Any) -> None:
    """Raises :class:`JobsError` for the first view of ``jobs`` (from :func:`read_jobs` of
    ``path``) that ``scene`` cannot render (an unknown camera, settings the render refuses:
    see :func:`penumbra.distributed.check_views`), naming it in the file."""
    from .distributed import check_views as check
    from .views import ViewError

    try:
        check(scene, jobs["views"])
    except ViewError as e:
        where = describe(path, jobs["origins"][e.index], e.index, e.name)
        raise JobsError(f"{where}: {e.reason}") from None


def view_line(r: Dict[str, Any]) -> str:
    """A view's line of the summary: name, image path, and how it went."""
    if r.get("error"):
        how = f"failed: {r['error']}"
    elif r["skipped"]:
        how = "skipped (done before: its record matches)"
    else:
        how = f"{r['seconds']:.2f} s, {r['rays_per_second'] / 1e6:.1f} Mrays/s"
    return f"{r['name']}\t{r['path']}\t{how}"


def open_manifest(path: Optional[str]) -> Any:
    """The manifest file opened for appending (its folder made) by the command line's code,
    whose ``append`` writes a line (JSON text of :func:`manifest_line`'s dict) with one
    ``write``; None without one. Raises ``OSError`` naming the file."""
    from . import _core

    return None if path is None else _core.Manifest(path)


def manifest_line(
    index: int, view: Dict[str, Any], r: Dict[str, Any], scene_seed: int
) -> Dict[str, Any]:
    """A view's line of the manifest, with the keys of ``penumbra render --manifest``'s:
    ``task``, ``camera`` (a camera name, else None), ``frame`` (None: views have no frame),
    ``seed``, ``seconds``, ``peak_memory_bytes`` and ``host`` (of the task's process; None
    for a skipped view), ``outputs``, ``attempts`` (None: Ray retries on its own),
    ``status`` (``rendered``, ``skipped`` or ``failed``) and ``error``."""
    from .views import aov_path

    outputs = [r["path"]] + ([aov_path(r["path"])] if view["aovs"] else [])
    camera = view["camera"]
    return {
        "task": index,
        "camera": camera if isinstance(camera, str) else None,
        "frame": None,
        "seed": view["seed"] if view["seed"] is not None else scene_seed,
        "seconds": r.get("seconds", 0.0),
        "peak_memory_bytes": r.get("peak_memory_bytes"),
        "host": r.get("host"),
        "outputs": outputs,
        "attempts": None,
        "status": "failed" if r.get("error") else "skipped" if r["skipped"] else "rendered",
        "error": r.get("error"),
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
    parser.add_argument(
        "--force", action="store_true", help="render every view, even those done before"
    )
    parser.add_argument(
        "--allow-path",
        action="append",
        default=[],
        metavar="DIR",
        help="let the scene's files also read files in DIR and below (repeatable), as "
        "`penumbra render --allow-path` does",
    )
    parser.add_argument(
        "--json",
        action="store_true",
        help="print the summary as one JSON object at the end (each view's line goes to stderr)",
    )
    parser.add_argument(
        "--quiet", "-q", action="store_true", help="no progress bar (nor, with --json, view lines)"
    )
    parser.add_argument(
        "--manifest",
        metavar="FILE.jsonl",
        help="append one JSON line per view as it ends, as `penumbra render --manifest` does",
    )
    parser.add_argument(
        "--meta",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="write each image's record beside it (OUT.meta.json), as `penumbra render --meta` "
        "does, and skip the views whose record matches (the default); --no-meta writes none "
        "and renders every view",
    )
    parser.add_argument(
        "--coco",
        metavar="FILE.json",
        help="write COCO annotations (boxes, RLE masks, visible fractions) of every view's "
        "object_id AOV to FILE.json at the end (needs pycocotools)",
    )
    args = parser.parse_args(argv)

    try:
        import penumbra
        import penumbra.distributed  # noqa: F401  (Ray, needed below)
    except ImportError as e:
        print(f"penumbra.batch: {e} (install Ray with `pip install .[ray]`)", file=sys.stderr)
        return 1
    try:
        jobs = read_jobs(args.jobs)
        scene = penumbra.load(jobs["scene"], allow_paths=args.allow_path)
        check_views(args.jobs, jobs, scene)
    except OSError as e:  # the jobs file or the scene file cannot be read
        what = f"{e.filename}: {e.strerror}" if e.filename and e.strerror else str(e)
        print(f"penumbra.batch: {what}", file=sys.stderr)
        return 2
    except ValueError as e:  # JobsError and penumbra.SceneError
        print(f"penumbra.batch: {e}", file=sys.stderr)
        return 2
    if args.coco is not None:
        from . import coco

        try:
            coco.check_available()
        except ImportError as e:
            print(f"penumbra.batch: --coco: {e}", file=sys.stderr)
            return 1
        missing = [i for i, v in enumerate(jobs["views"]) if "object_id" not in v["aovs"]]
        if missing:
            i = missing[0]
            where = describe(args.jobs, jobs["origins"][i], i, jobs["views"][i]["name"])
            print(
                f"penumbra.batch: --coco: {where}: has no object_id AOV to annotate (add "
                f'aovs = ["object_id"] to its view or to [defaults])',
                file=sys.stderr,
            )
            return 2
    try:
        args.manifest_file = open_manifest(args.manifest)
    except OSError as e:  # "FILE: cannot write the manifest: ..."
        print(f"penumbra.batch: --manifest {e}", file=sys.stderr)
        return 2
    try:
        if args.json:
            with _stdout_to_stderr() as out:
                code, summary = _run(args, jobs, scene)
                if code == 0:
                    json.dump({"views": summary}, out, indent=1)
                    print(file=out)
            return code
        return _run(args, jobs, scene)[0]
    finally:
        if args.manifest_file is not None:
            args.manifest_file.close()


@contextlib.contextmanager
def _stdout_to_stderr() -> Iterator[TextIO]:
    """Standard output kept for the JSON summary alone: meanwhile file descriptor 1 is
    standard error, so whatever else writes to it (this process, Ray's processes started now,
    which inherit it, and worker messages such as a worker that died) goes to stderr. Yields
    the real standard output."""
    sys.stdout.flush()
    saved = os.dup(1)
    os.dup2(2, 1)
    try:
        with os.fdopen(os.dup(saved), "w") as out:
            yield out
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


def _run(
    args: argparse.Namespace, jobs: Dict[str, Any], scene: Any
) -> Tuple[int, List[Dict[str, Any]]]:
    """Renders the batch on Ray: the exit status and the summary."""
    from penumbra import distributed

    # Each view's line as it finishes: the results on stdout, or beside --json's summary (at
    # the end, on stdout) as progress on stderr, which --quiet silences.
    lines = sys.stderr if args.json else sys.stdout

    index = {v["name"]: i for i, v in enumerate(jobs["views"])}

    def finished(r: Dict[str, Any]) -> None:
        if not (args.json and args.quiet):
            print(view_line(r), file=lines, flush=True)
        if args.manifest_file is not None:
            i = index[r["name"]]
            line = manifest_line(i, jobs["views"][i], r, scene.settings["seed"])
            args.manifest_file.append(json.dumps(line))

    cpus, what = jobs["cpus_per_task"], f"{args.jobs}: cpus_per_task"
    if args.cpus_per_task is not None:
        cpus, what = args.cpus_per_task, "--cpus-per-task"
    try:
        distributed.connect(args.address, num_cpus=args.num_cpus)
        distributed.check_num_cpus(cpus, what)
        summary = distributed.render_views(
            scene,
            jobs["views"],
            output=jobs["output"],
            num_cpus=cpus,
            force=args.force,
            progress=not args.quiet and sys.stderr.isatty() or None,
            on_view=finished,
            keep_going=True,
            meta=args.meta,
        )
    except KeyboardInterrupt:
        print("penumbra.batch: interrupted", file=sys.stderr)
        return 130, []
    except ValueError as e:
        print(f"penumbra.batch: {e}", file=sys.stderr)
        return 2, []
    except Exception as e:  # the cluster, a task or a write failed
        print(f"penumbra.batch: {type(e).__name__}: {e}", file=sys.stderr)
        return 1, []
    finally:
        if args.address == "local":
            import ray

            ray.shutdown()
    failures = [r for r in summary if r.get("error")]
    if failures:
        # The others are done; the failed ones are listed last, as the command line does.
        print(f"penumbra.batch: {len(failures)} of {len(summary)} views failed:", file=sys.stderr)
        for r in failures:
            print(f"  {r['name']}: {r['error']}", file=sys.stderr)
        return 1, summary
    if args.coco is not None:
        try:
            write_coco(args.coco, scene, jobs["views"], summary)
            if not args.quiet:
                print(f"penumbra.batch: wrote {args.coco}", file=sys.stderr)
        except (OSError, ValueError) as e:
            print(f"penumbra.batch: --coco {args.coco}: {e}", file=sys.stderr)
            return 1, summary
    return 0, summary


def write_coco(
    path: str, scene: Any, views: Sequence[Dict[str, Any]], summary: Sequence[Dict[str, Any]]
) -> None:
    """Writes the COCO annotations (:func:`penumbra.coco.write_annotations`) of every view
    of the batch, read back from its ``.aovs.npz``, to ``path``: file names relative to its
    folder, visible fractions from each view's camera."""
    import numpy as np

    from . import coco
    from .views import aov_path

    folder = os.path.dirname(os.path.abspath(path))
    images = []
    for v, r in zip(views, summary):
        with np.load(aov_path(r["path"])) as aovs:
            if "object_id" not in aovs:
                raise ValueError(f"{aov_path(r['path'])}: no object_id array")
            ids = aovs["object_id"]
        images.append(
            {
                "file_name": os.path.relpath(os.path.abspath(r["path"]), folder),
                "object_id": ids,
                "camera": v["camera"],
            }
        )
    coco.write_annotations(path, scene, images)


if __name__ == "__main__":
    sys.exit(main())
