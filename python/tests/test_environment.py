"""Environment, directional and spot lights from Python: load_dict takes them as a scene file
does, and a scene's pack carries its HDR map, so that another process renders the same image
without the file."""

import pickle
import struct
import zlib

import numpy as np
import pytest

import penumbra


def scene(light):
    return {
        "film": {"width": 24, "height": 16},
        "camera": {"position": [0, 3, 5], "look_at": [0, 0, 0], "fov": 50},
        "render": {"light_model": "physical", "ambient": 0},
        "materials": {"white": {"diffuse": 1}},
        "lights": [light],
        "objects": [
            {"type": "quad", "material": "white", "corner": [-9, 0, -9], "u": [18, 0, 0],
             "v": [0, 0, 18]},
        ],
    }


def test_a_uniform_sky_lights_a_white_floor_to_one():
    image = penumbra.load_dict(scene({"type": "environment", "color": [1, 1, 1]})).render(
        threads=2)
    floor = image[12:, :, 0]
    assert abs(float(floor.mean()) - 1.0) < 0.05


def test_a_sun_and_a_spot_load_from_a_dict():
    sun = penumbra.load_dict(scene({"type": "directional", "direction": [0, -1, 0],
                                    "intensity": float(np.pi)}))
    assert np.allclose(sun.render(threads=2)[12:, :, 0], 1.0, atol=1e-4)
    spot = penumbra.load_dict(scene({"type": "spot", "position": [0, 2, 0],
                                     "direction": [0, -1, 0], "outer_angle": 10}))
    image = spot.render(threads=2)
    assert image[..., 0].max() > 0 and image[0, 0, 0] == 0


def write_png(path, rgb):
    """An 8-bit RGB PNG of the (H, W, 3) uint8 array `rgb`."""
    h, w, _ = rgb.shape

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    rows = b"".join(b"\x00" + rgb[y].tobytes() for y in range(h))
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b"")
    path.write_bytes(png)


def test_a_pack_carries_the_map(tmp_path):
    # An 8-bit PNG map is read through the sRGB curve: 255 is radiance 1. Brighter on top.
    sky = np.zeros((4, 8, 3), np.uint8)
    sky[:2] = 255
    write_png(tmp_path / "sky.png", sky)
    s = penumbra.load_dict(scene({"type": "environment", "file": "sky.png", "samples": 4}),
                           base_dir=tmp_path)
    before = s.render(threads=2)
    (tmp_path / "sky.png").unlink()
    again = pickle.loads(pickle.dumps(s))
    assert np.array_equal(again.render(threads=2), before)
    with pytest.raises(penumbra.SceneError, match="sky.png"):
        penumbra.load_dict(scene({"type": "environment", "file": "sky.png"}), base_dir=tmp_path)
