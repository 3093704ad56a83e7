"""Threads, the GIL, Ctrl-C and progress: renders run with the GIL released, stop within
about 0.1 s of Ctrl-C, and report progress on the calling thread."""

from __future__ import annotations

import io
import os
import signal
import sys
import threading
import time
import types
import _thread

import numpy as np
import pytest

import penumbra
from conftest import SCENES

# Big enough to take many seconds on any machine: ~1 M pixels × 16 samples × 100 light samples.
LONG = dict(width=1024, height=1024, spp=16, light_samples=10)


@pytest.fixture(scope="module")
def cornell() -> penumbra.Scene:
    return penumbra.load(SCENES / "cornell.toml")


def interrupt_after(seconds: float, how) -> dict:
    sent = {}

    def fire():
        time.sleep(seconds)
        sent["at"] = time.perf_counter()
        how()

    threading.Thread(target=fire, daemon=True).start()
    return sent


@pytest.mark.usefixtures("sigint_raises")
@pytest.mark.parametrize(
    "how",
    [_thread.interrupt_main, lambda: os.kill(os.getpid(), signal.SIGINT)],
    ids=["interrupt_main", "SIGINT"],
)
def test_ctrl_c_stops_a_long_render_fast(cornell, how):
    sent = interrupt_after(0.3, how)
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        cornell.render(threads=2, **LONG)
    raised = time.perf_counter()
    assert raised - start > 0.25  # it was interrupted, not refused
    latency = raised - sent["at"]
    print(f"KeyboardInterrupt {1000 * latency:.0f} ms after the signal")
    assert latency < 0.25, latency
    # The scene renders normally afterwards.
    assert cornell.render(width=8, height=8).shape == (8, 8, 3)


def test_the_gil_is_released_while_rendering(cornell):
    counts = []
    stop = threading.Event()

    def count():
        n = 0
        while not stop.is_set():
            n += 1
            if n % 1000 == 0:
                counts.append(n)

    t = threading.Thread(target=count)
    t.start()
    try:
        before = len(counts)
        cornell.render(width=128, height=128, spp=4, threads=1)
        during = len(counts) - before
    finally:
        stop.set()
        t.join()
    # A Python thread kept running throughout the render.
    assert during > 10, during


def test_a_progress_callable_runs_on_the_calling_thread(cornell):
    calls = []
    me = threading.get_ident()

    def progress(done, total):
        calls.append((done, total, threading.get_ident()))

    cornell.render(width=160, height=120, spp=16, threads=2, progress=progress)
    assert calls, "no progress reported"
    assert all(ident == me for _, _, ident in calls)
    assert all(total == 160 * 120 for _, total, _ in calls)
    done = [d for d, _, _ in calls]
    assert done == sorted(done) and done[-1] == 160 * 120


def test_an_exception_in_the_progress_callable_stops_the_render(cornell):
    def progress(done, total):
        raise RuntimeError("stop here")

    start = time.perf_counter()
    with pytest.raises(RuntimeError, match="stop here"):
        cornell.render(threads=2, **LONG, progress=progress)
    assert time.perf_counter() - start < 5


class Terminal(io.StringIO):
    """Standard error as a terminal."""

    def isatty(self) -> bool:
        return True


def test_progress_true_shows_a_tqdm_bar_on_a_terminal_only(cornell, capsys, monkeypatch):
    pytest.importorskip("tqdm")
    # To a file or a pipe (pytest's capture): nothing, not one line per redraw.
    image = cornell.render(width=64, height=64, spp=4, progress=True)
    assert image.shape == (64, 64, 3)
    assert capsys.readouterr().err == ""
    terminal = Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    cornell.render(width=64, height=64, spp=4, progress=True)
    assert "render:" in terminal.getvalue() and "px" in terminal.getvalue()


def test_progress_true_shows_a_bar_in_ipython_whatever_its_stderr(cornell, capsys, monkeypatch):
    # A kernel's stderr is no terminal, and its front end draws tqdm's redraws in place.
    pytest.importorskip("tqdm")
    shell = types.ModuleType("IPython")
    shell.get_ipython = lambda: object()
    monkeypatch.setitem(sys.modules, "IPython", shell)
    cornell.render(width=16, height=16, spp=1, progress=True)
    assert "render:" in capsys.readouterr().err


def test_progress_true_without_tqdm_warns_how_to_install_it(cornell, monkeypatch):
    # As after a plain `pip install .`: tqdm cannot be imported.
    monkeypatch.setitem(sys.modules, "tqdm", None)
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    with pytest.warns(RuntimeWarning, match=r"pip install tqdm.*\[progress\]") as caught:
        image = cornell.render(width=16, height=16, spp=1, progress=True)
    assert image.shape == (16, 16, 3)
    # The warning points at the line that asked for the bar.
    assert caught[0].filename == __file__


def test_passes_show_the_image_so_far_and_end_in_the_image_of_one_pass(cornell):
    once = cornell.render(width=48, height=40, spp=16, threads=2)
    me = threading.get_ident()
    seen = []

    def passes(samples, image):
        seen.append((samples, image.copy(), threading.get_ident()))

    final = cornell.render(width=48, height=40, spp=16, threads=2, passes=passes)
    assert np.array_equal(final.view(np.uint32), once.view(np.uint32)), "bit for bit"
    # The preview (0: the first sample of the even rows, each shown twice), 1, 2, 4, 8.
    assert [s for s, _, _ in seen] == [0, 1, 2, 4, 8]
    preview, one = seen[0][1], seen[1][1]
    assert np.array_equal(preview[0::2], one[0::2]) and np.array_equal(preview[1::2], preview[0::2])
    assert all(ident == me for _, _, ident in seen)
    assert all(img.shape == (40, 48, 3) and img.dtype == np.float32 for _, img, _ in seen)
    # Each pass is nearer the final image than the first one is.
    errors = [float(np.abs(img - once).mean()) for _, img, _ in seen]
    assert errors[-1] < errors[0]


def test_passes_and_aovs_are_refused_together(cornell):
    with pytest.raises(ValueError, match="passes"):
        cornell.render(width=8, height=8, passes=lambda s, img: None, aovs="depth")
