"""Shared helpers: the repository's paths, the command-line binary and a PFM reader."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"


def cli_binary() -> Path:
    """The `penumbra` binary: $PENUMBRA_CLI, else the one cargo built in target/."""
    env = os.environ.get("PENUMBRA_CLI")
    if env:
        return Path(env)
    for profile in ("debug", "release"):
        p = ROOT / "target" / profile / "penumbra"
        if p.exists():
            return p
    found = shutil.which("penumbra")
    if found:
        return Path(found)
    pytest.skip("no penumbra binary: set PENUMBRA_CLI or run `cargo build -p penumbra-cli`")


def run_cli(*args: object) -> subprocess.CompletedProcess:
    """Runs the command line; fails the test on a nonzero exit."""
    out = subprocess.run(
        [str(cli_binary()), *map(str, args)], capture_output=True, text=True, check=False
    )
    assert out.returncode == 0, out.stderr
    return out


def read_pfm(path: Path) -> np.ndarray:
    """A colour PFM as an (H, W, 3) float32 array, row 0 at the top."""
    data = path.read_bytes()
    header, rest = data.split(b"\n", 1)
    assert header == b"PF"
    size, rest = rest.split(b"\n", 1)
    scale, rest = rest.split(b"\n", 1)
    width, height = map(int, size.split())
    dtype = "<f4" if float(scale) < 0 else ">f4"
    rows = np.frombuffer(rest, dtype=dtype).reshape(height, width, 3)
    return rows[::-1].astype(np.float32)


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """True when two float32 arrays hold the same bits (so NaNs and signed zeros count)."""
    return a.shape == b.shape and bool(
        np.array_equal(a.view(np.uint32), np.ascontiguousarray(b, np.float32).view(np.uint32))
    )
