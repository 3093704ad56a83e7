#!/usr/bin/env bash
# The one test command: every Rust test, then the Python package built as `pip install .`
# builds it and tested with pytest (python/tests and the examples of docs/python.md).
#
#   tools/test.sh              # everything
#   tools/test.sh -k aov       # extra arguments go to pytest
#
# Needs the Rust toolchain and Python 3.9+ with pip; the first run downloads maturin, numpy,
# pytest, tqdm, Ray, trimesh, pycocotools (COCO's RLE masks, which penumbra.coco uses when it is
# there) and a Jupyter kernel (nbclient, ipykernel) from PyPI into a virtual environment under
# target/ (kept between runs;
# PENUMBRA_TEST_VENV picks another place). The extension is built with cargo's dev profile
# (opt-level 2), not LTO'd release: pyo3's macros turn on syn features that serde's derive
# shares, so its build compiles the library once more, and at opt-level 2 that is quick;
# PENUMBRA_PY_PROFILE=release builds it as a plain `pip install .` does.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$SECONDS

# penumbra-py has no Rust tests; maturin builds it below. Leaving it out here keeps this build's
# features those of `cargo run` (pyo3's macros would turn on syn features that serde's derive
# shares, and so rebuild the library), so the README's render command's build is reused.
cargo test --workspace --exclude penumbra-py
# The binary the Python tests compare images with (the CLI's tests have built it already).
cargo build -p penumbra-cli
cli="$PWD/target/debug/penumbra"

venv="${PENUMBRA_TEST_VENV:-target/py-test-venv}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv" || {
        # Some distributions ship Python without the venv module.
        python3 -m pip install --quiet --user virtualenv && python3 -m virtualenv --quiet "$venv"
    }
fi
venv="$(cd "$venv" && pwd)"
py="$venv/bin/python"
# trimesh (pinned; Pillow for its textures) reads the shared glTF and PLY files as a reference;
# OpenCV (headless, pinned) is the reference for the lens models' projections;
# nbclient and ipykernel run the example notebook in a real kernel.
"$py" -m pip install --quiet "maturin>=1.5,<2" "numpy>=1.21" pytest tqdm "ray>=2.9" \
    "tomli>=1.1; python_version < '3.11'" "trimesh==4.5.3" "pillow>=9" \
    "nbclient>=0.10" "nbformat>=5.9" "ipykernel>=6.29" "pycocotools>=2.0.8" \
    "opencv-python-headless==4.10.0.84"

profile="${PENUMBRA_PY_PROFILE:-dev}"
PATH="$venv/bin:$PATH" MATURIN_PEP517_ARGS="--profile $profile" \
    "$py" -m pip install --quiet --no-build-isolation --no-deps --force-reinstall .

# python/ is not on sys.path: the tests import the installed package.
# The Ray tests start their own local clusters; without Ray they fail rather than skip.
PENUMBRA_REQUIRE_RAY=1 PENUMBRA_CLI="$cli" "$py" -m pytest -q -p no:cacheprovider --rootdir "$PWD" \
    -c "$PWD/pyproject.toml" "$PWD/python/tests" "$PWD/docs/python.md" "$@"

echo "tools/test.sh: all tests passed in $((SECONDS - start)) s"
