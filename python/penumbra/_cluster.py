"""Joining a Ray cluster, and what it can run: :func:`connect` starts or joins one, and
:func:`check_num_cpus` refuses tasks larger than any node.
"""

from __future__ import annotations

import logging
import numbers
import socket
from typing import Optional

import numpy as np
import ray

from . import _args


def connect(address: str = "local", num_cpus: Optional[int] = None, timeout: float = 5.0) -> None:
    """Start or join Ray: ``"local"`` starts a private instance on this machine (with
    ``num_cpus`` CPUs, default all; with Ray's token authentication, on by default since Ray
    2.5x, without Ray's notice saying so on every run: ``RAY_AUTH_MODE=disabled`` turns it
    off), ``"auto"`` joins the cluster this machine is part of, and
    ``"HOST:PORT"`` the cluster whose head listens there. An address that does not answer
    within ``timeout`` seconds raises ``ConnectionError`` at once, naming it."""
    num_cpus = _args.optional_integer("connect", "num_cpus", num_cpus, 1, _args.U32_MAX)
    timeout = _args.finite("connect", "timeout", timeout, positive=True)
    if ray.is_initialized():
        return
    if address == "local":
        # Ray turns token authentication on for a new local instance (other users of the
        # machine cannot run code on it) and warns so on every run: kept on, unannounced.
        auth = logging.getLogger(TOKEN_LOGGER)
        auth.addFilter(_no_token_notice)
        try:
            ray.init(num_cpus=num_cpus, include_dashboard=False, log_to_driver=False)
        finally:
            auth.removeFilter(_no_token_notice)
        return
    if address != "auto":
        host, sep, port = address.rpartition(":")
        if not sep or not host or not port.isdigit():
            raise ValueError(f"a Ray address is local, auto or HOST:PORT, not {address!r}")
        try:
            socket.create_connection((host, int(port)), timeout=timeout).close()
        except OSError as e:
            raise ConnectionError(f"no Ray cluster answers at {address}: {e}") from None
    try:
        ray.init(address=address, log_to_driver=False)
    except ConnectionError as e:
        raise ConnectionError(f"cannot join the Ray cluster at {address}: {e}") from None


#: The logger of Ray's notice that a new local instance has token authentication on.
TOKEN_LOGGER = "ray._private.authentication.authentication_token_setup"


def _no_token_notice(record: logging.LogRecord) -> bool:
    """False for Ray's "Token authentication is enabled" notice, which a private local
    instance would print on every run; its other messages pass."""
    return not record.getMessage().startswith("Token authentication is enabled")


def check_num_cpus(num_cpus: float, what: str = "num_cpus") -> None:
    """Raises ``ValueError`` naming ``what`` unless ``num_cpus`` is a positive number of CPUs
    that some live node of the cluster has: a task asking for more than any node has would
    wait forever (Ray queues it silently)."""
    if isinstance(num_cpus, (bool, np.bool_)) or not isinstance(num_cpus, numbers.Real):
        raise ValueError(f"{what} must be a positive number of CPUs, not {num_cpus!r}")
    if not 0 < num_cpus < float("inf"):
        raise ValueError(f"{what} must be a positive number of CPUs, not {num_cpus!r}")
    most = max(
        (n["Resources"].get("CPU", 0) for n in ray.nodes() if n.get("Alive")), default=0
    )
    if num_cpus > most:
        raise ValueError(
            f"{what} is {num_cpus:g} CPUs per task, more than any node of the cluster has "
            f"(at most {most:g}): its tasks would wait forever"
        )
