"""The package's own documentation: every public name has a docstring, and the examples in
docstrings run (docs/python.md's examples run through pytest's --doctest-glob)."""

from __future__ import annotations

import doctest
import inspect
import re
from importlib.metadata import version

import pytest

import penumbra
from penumbra import _camera, _image, _pack, _raycast, _scene, _tensor, coco, poses, record, views

from conftest import ROOT

MODULES = [penumbra, _camera, _image, _pack, _raycast, _scene, _tensor, views, poses, record, coco]


@pytest.mark.parametrize("module", MODULES, ids=lambda m: m.__name__)
def test_docstring_examples_run(module):
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
    if module is not _pack:
        assert result.attempted > 0


def test_every_public_name_is_documented():
    undocumented = []
    for name in penumbra.__all__:
        obj = getattr(penumbra, name)
        if inspect.isclass(obj) or inspect.isfunction(obj):
            if not (obj.__doc__ or "").strip():
                undocumented.append(name)
            for member, value in vars(obj).items():
                if member.startswith("_"):
                    continue
                if isinstance(value, property) or inspect.isfunction(value):
                    if not (value.__doc__ or "").strip():
                        undocumented.append(f"{name}.{member}")
    assert undocumented == []


def public_undocumented(module) -> list:
    """The public functions and classes defined in ``module`` that have no docstring."""
    return [
        name
        for name, obj in vars(module).items()
        if not name.startswith("_")
        and getattr(obj, "__module__", None) == module.__name__
        and (inspect.isclass(obj) or inspect.isfunction(obj))
        and not (obj.__doc__ or "").strip()
    ]


def test_the_batch_modules_are_documented():
    from penumbra import batch

    assert public_undocumented(views) == [] and public_undocumented(batch) == []
    assert public_undocumented(record) == [] and public_undocumented(coco) == []
    assert set(penumbra.__all__) >= {"load", "loads", "load_dict", "Scene", "Camera", "SceneError", "RaycastingScene", "INVALID_ID"}


def test_the_version_is_the_cargo_workspaces():
    workspace = (ROOT / "Cargo.toml").read_text().split("[workspace.package]", 1)[1]
    cargo = re.search(r'^version = "([^"]+)"', workspace, re.M).group(1)
    assert penumbra.__version__ == cargo == version("penumbra")


def test_the_jobs_file_in_the_docs_is_the_example_file():
    doc = (ROOT / "docs" / "distributed.md").read_text()
    shown = doc.split("(../scenes/batch/orbit.toml), whole:\n\n```toml\n", 1)[1].split("```", 1)[0]
    assert shown == (ROOT / "scenes" / "batch" / "orbit.toml").read_text()
