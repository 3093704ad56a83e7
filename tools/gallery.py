#!/usr/bin/env python3
"""The README's gallery, from the README itself: each row of its gallery tables pairs an image
under docs/images/ with the command that renders it, and this script runs those commands.

    python3 tools/gallery.py            # render every gallery image anew into docs/images/
    python3 tools/gallery.py --check    # render each into a temporary folder and compare bytes

A row reads ``| ![alt](docs/images/NAME.png) | `cargo run --release -- render ARGS -o out/X.png` ... |``.
The command runs from the repository's root as written, except that its ``-o`` path is
replaced by the image's path (or a temporary one with --check); the binary is $PENUMBRA_CLI, or
the release build, which the script builds with cargo when PENUMBRA_CLI is not set. Renders are
deterministic, so --check (and python/tests/test_gallery.py, which runs it per image) fails
exactly when an image no longer matches its command. Standard library only.
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import List, Sequence

ROOT = Path(__file__).resolve().parents[1]
ROW = re.compile(
    r"^\|\s*!\[[^\]]*\]\((?P<image>docs/images/[^)\s]+\.png)\)\s*\|\s*"
    r"`cargo run --release -- (?P<args>render [^`]+)`"
)


@dataclass(frozen=True)
class Entry:
    """One gallery image and the CLI arguments of the README's command for it."""

    image: str
    args: List[str]

    def arguments(self, output: Path) -> List[str]:
        """The command's arguments with its -o path replaced by ``output``."""
        args = list(self.args)
        for flag in ("-o", "--output", "--outfile"):
            if flag in args:
                args[args.index(flag) + 1] = str(output)
                return args
        return args + ["-o", str(output)]


def entries(readme: Path = ROOT / "README.md") -> List[Entry]:
    """Every gallery row of ``readme``, in order."""
    found = []
    for line in readme.read_text(encoding="utf-8").splitlines():
        m = ROW.match(line)
        if m:
            found.append(Entry(m["image"], shlex.split(m["args"])))
    if not found:
        raise SystemExit(f"{readme}: no gallery rows found")
    return found


def cli_binary() -> Path:
    """$PENUMBRA_CLI, else the release binary, built first."""
    env = os.environ.get("PENUMBRA_CLI")
    if env:
        return Path(env)
    subprocess.run(["cargo", "build", "--release", "-p", "penumbra-cli"], cwd=ROOT, check=True)
    return ROOT / "target" / "release" / "penumbra"


def render(binary: Path, entry: Entry, output: Path) -> None:
    """Runs the entry's command with its output at ``output``; raises on failure."""
    cmd = [str(binary), *entry.arguments(output), "--quiet"]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({done.returncode}): {done.stderr.strip()}")


def check(binary: Path, entry: Entry) -> bool:
    """True when ``entry``'s command renders its image byte for byte."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / Path(entry.image).name
        render(binary, entry, out)
        return out.read_bytes() == (ROOT / entry.image).read_bytes()


def main(argv: Sequence[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true", help="compare instead of writing")
    args = parser.parse_args(argv)
    binary = cli_binary()
    stale = []
    for entry in entries():
        if args.check:
            if not check(binary, entry):
                stale.append(entry.image)
        else:
            render(binary, entry, ROOT / entry.image)
        print(f"{entry.image}: {'stale' if entry.image in stale else 'ok'}", file=sys.stderr)
    if stale:
        print(f"{len(stale)} gallery images differ from their commands: "
              "run python3 tools/gallery.py", file=sys.stderr)
    return 1 if stale else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
