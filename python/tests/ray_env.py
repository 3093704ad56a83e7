"""Ray for the tests: a real local cluster on loopback only, started by the tests themselves.

Importing this module sets what Ray needs on this kind of machine before Ray is imported: no
usage statistics, every address 127.0.0.1, no authentication. It skips the importing test
module when Ray is not installed, unless PENUMBRA_REQUIRE_RAY is set (tools/test.sh sets it,
so that CI fails instead of silently skipping).
"""

from __future__ import annotations

import os

import pytest

ENV = {
    "RAY_USAGE_STATS_ENABLED": "0",
    "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0",
    "RAY_AUTH_MODE": "disabled",
}
for key, value in ENV.items():
    os.environ.setdefault(key, value)

if os.environ.get("PENUMBRA_REQUIRE_RAY"):
    import ray  # noqa: F401  (fails loudly when required but missing)
else:
    ray = pytest.importorskip("ray")
