"""Shared helpers: the repository's paths, the command-line binary, a PFM reader, and the
fixture that makes Ctrl-C raise KeyboardInterrupt whoever started the tests."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
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


@pytest.fixture
def sigint_raises():
    """Python's own SIGINT handler (KeyboardInterrupt) for the test's duration. A Python
    started with SIGINT ignored (from a non-interactive script, as a background job `cmd &`,
    under nohup) keeps ignoring it and never raises KeyboardInterrupt, so a test that sends
    SIGINT to itself needs this."""
    before = signal.getsignal(signal.SIGINT)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


def python_with_sigint(*args: str) -> list:
    """The command that runs ``python -m ARGS`` with Python's own SIGINT handler installed
    first, for a child that the test interrupts: a child inherits an ignored SIGINT from a
    test run started in the background, and would not stop."""
    module, *rest = args
    code = (
        "import runpy, signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
        f"sys.argv = [{module!r}] + sys.argv[1:]; runpy.run_module({module!r}, run_name='__main__')"
    )
    return [sys.executable, "-c", code, *rest]
