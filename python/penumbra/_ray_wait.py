"""Waiting for Ray tasks on the driver: results handled as they arrive, under a progress bar;
a failed task named in one line, not Ray's remote traceback; Ctrl-C cancelling the rest.
"""

from __future__ import annotations

import re
import signal
import threading
from typing import Any, Callable, Dict, List, Optional, Tuple

import ray

from ._scene import progress_bar


def gather(
    refs: List["ray.ObjectRef"],
    on_result: Callable[[int, Dict[str, Any]], None],
    progress: Any,
    unit: str,
    label: Callable[[int], str],
    on_failure: Optional[Callable[[int, Exception], None]] = None,
) -> None:
    """Waits for every task, calling ``on_result(index, result)`` as each finishes (with a
    progress bar cleared meanwhile, so that what it prints stays readable); cancels the rest
    on any error or Ctrl-C. A task that failed (after Ray's retries) raises one line naming
    it by ``label(index)`` (see :func:`task_failure`), not Ray's remote traceback; with
    ``on_failure``, that error, or one ``on_result`` raised, goes to ``on_failure(index,
    error)`` instead and the other tasks go on."""
    index = {ref: i for i, ref in enumerate(refs)}
    pending = list(refs)
    bar = _bar(progress, len(refs), unit)
    interrupted, previous = _defer_ctrl_c()
    try:
        while pending:
            if interrupted.is_set():
                raise KeyboardInterrupt
            done, pending = ray.wait(pending, num_returns=1, timeout=0.5)
            for ref in done:
                try:
                    result = ray.get(ref)
                except ray.exceptions.RayError as e:
                    failure = task_failure(e, label(index[ref]))
                    if on_failure is None:
                        raise failure from None
                    on_failure(index[ref], failure)
                    continue
                try:
                    if bar is None:
                        on_result(index[ref], result)
                    else:
                        with bar.external_write_mode():
                            on_result(index[ref], result)
                except Exception as e:
                    if on_failure is None:
                        raise
                    on_failure(index[ref], e)
                if bar is not None:
                    bar.update(1)
                elif callable(progress):
                    progress(len(refs) - len(pending), len(refs))
    except BaseException:
        for ref in pending:
            ray.cancel(ref, force=True)
        raise
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
        if bar is not None:
            bar.close()


def _defer_ctrl_c() -> Tuple[threading.Event, Any]:
    """An event that Ctrl-C sets while tasks are awaited, instead of raising
    KeyboardInterrupt wherever the main thread happens to be: raised inside Ray's calls, it
    made Ray's core worker abort now and then ("Tried to complete task that was not pending"),
    so the batch died with a crash report instead of exiting 130. :func:`gather` raises it
    itself between waits (within 0.5 s). Only Python's default handler is replaced, and only on
    the main thread, where handlers live; the handler it replaced is returned (or None)."""
    event = threading.Event()
    if (
        threading.current_thread() is threading.main_thread()
        and signal.getsignal(signal.SIGINT) is signal.default_int_handler
    ):
        return event, signal.signal(signal.SIGINT, lambda *_: event.set())
    return event, None


# Terminal escape sequences (colours) in Ray's messages.
_ESCAPES = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]|[\x00-\x08\x0b-\x1f\x7f]")


def task_failure(e: "ray.exceptions.RayError", what: str) -> Exception:
    """One line for a failed task: ``WHAT: message`` of the exception the task raised (of its
    type when it is a ValueError, MemoryError or OSError, else a RuntimeError), or the first
    line of Ray's own error (a worker that died more often than it was retried), without
    Ray's remote traceback or terminal escape codes."""
    cause = getattr(e, "cause", None)
    err = cause if isinstance(cause, Exception) else e
    lines = [line.strip() for line in _ESCAPES.sub("", str(err)).splitlines() if line.strip()]
    message = f"{what}: {type(err).__name__}: {lines[0] if lines else 'failed'}"
    kind = type(err) if isinstance(err, (ValueError, MemoryError, OSError)) else RuntimeError
    try:
        return kind(message)
    except TypeError:  # a subclass with other arguments
        return RuntimeError(message)


def _bar(progress: Any, total: int, unit: str) -> Any:
    if progress is not True:
        return None
    # _bar <- gather <- render_frame or render_views <- the caller's line.
    return progress_bar(stacklevel=4, total=total, unit=unit, desc="penumbra", leave=False)
