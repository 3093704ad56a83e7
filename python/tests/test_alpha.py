"""Coverage alpha from Python (docs/scene-format.md, "Alpha"): ``render(alpha=True)`` returns
premultiplied RGBA whose alpha is the hit mask with one centred sample; ``write_image`` and
``to_srgb8`` give PNG's straight alpha, read back here by OpenCV; formats without alpha are
refused; batches take ``alpha`` as a view setting."""

from __future__ import annotations

import cv2  # the test extra's independent PNG reader
import numpy as np
import pytest

import penumbra
from penumbra.views import setting_problem


def scene(sampler: str = "center") -> penumbra.Scene:
    return penumbra.load_dict({
        "film": {"width": 40, "height": 30},
        "camera": {"position": [0.3, 0.4, 5], "look_at": [0.1, 0, 0], "fov": 40},
        "render": {"sampler": sampler, "background": [1, 0, 0]},
        "lights": [{"type": "point", "position": [2, 3, 4]}],
        "objects": [
            {"type": "cube", "center": [-0.6, -0.1, 0], "size": 1.1, "rotate": [10, 35, 5]},
            {"type": "sphere", "center": [0.9, 0.35, -0.4], "radius": 0.6},
        ],
    })


def test_alpha_is_the_hit_mask_and_misses_leave_the_colour():
    s = scene()
    assert s.settings["alpha"] is False
    rgba, aovs = s.render(alpha=True, aovs=["depth"])
    assert rgba.shape == (30, 40, 4) and rgba.dtype == np.float32
    mask = np.isfinite(aovs["depth"]).astype(np.float32)
    np.testing.assert_array_equal(rgba[..., 3], mask)
    assert 0 < mask.mean() < 1
    opaque = s.render()
    assert opaque.shape == (30, 40, 3)
    # The transparent image over the background is the opaque one.
    over = rgba[..., :3] + (1 - rgba[..., 3:]) * np.array([1, 0, 0], np.float32)
    np.testing.assert_allclose(over, opaque, atol=1e-5)
    assert not rgba[mask == 0].any()


def test_rgss_alpha_counts_quarters():
    rgba = scene("rgss").render(alpha=True)
    quarters = rgba[..., 3] * 4
    np.testing.assert_array_equal(quarters, np.round(quarters))
    assert ((quarters > 0) & (quarters < 4)).any()


def test_png_holds_straight_alpha(tmp_path):
    rgba = scene("rgss").render(alpha=True)
    path = tmp_path / "a.png"
    penumbra.write_image(path, rgba)
    bgra = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    assert bgra.shape == (30, 40, 4) and bgra.dtype == np.uint8
    a = rgba[..., 3]
    np.testing.assert_array_equal(bgra[..., 3], np.round(a * 255).astype(np.uint8))
    straight = np.where(a[..., None] > 0, rgba[..., :3] / np.maximum(a, 1e-30)[..., None], 0)
    want = penumbra.to_srgb8(straight.astype(np.float32))
    np.testing.assert_array_equal(bgra[..., 2::-1], want)
    np.testing.assert_array_equal(penumbra.to_srgb8(rgba), bgra[..., [2, 1, 0, 3]])


@pytest.mark.parametrize("name", ["a.jpg", "a.pfm"])
def test_formats_without_alpha_are_refused(tmp_path, name):
    rgba = scene().render(alpha=True)
    with pytest.raises(ValueError, match="no alpha channel"):
        penumbra.write_image(tmp_path / name, rgba)
    assert not list(tmp_path.iterdir())


def test_alpha_is_a_view_setting():
    assert setting_problem("alpha", True) is None
    assert "alpha must be true or false" in setting_problem("alpha", 1)
    with pytest.raises(TypeError, match="alpha must be True or False"):
        scene().render(alpha="yes")
