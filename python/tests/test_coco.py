"""COCO annotations from the object_id AOV (issue 28): boxes, areas and visible fractions
computed without pycocotools, checked by hand and against renders; the RLE masks, when
pycocotools is installed, decode back to the id AOV."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

import penumbra
from penumbra import coco

from conftest import SCENES

# A quad at z = 0 and a sphere in front of it; the quad's edges fall between pixel centres.
WALL = {"type": "quad", "corner": [-1.37, -1.11, 0], "u": [2.71, 0, 0], "v": [0, 2.23, 0]}
BALL = {"type": "sphere", "center": [0.3, 0.1, 1], "radius": 0.6}


def scene_of(*objects):
    return penumbra.load_dict(
        {
            "film": {"width": 40, "height": 30},
            "camera": {"position": [0, 0, 6], "look_at": [0, 0, 0], "fov": 40},
            "lights": [{"type": "point", "position": [0, 0, 6]}],
            "objects": list(objects),
        }
    )


def ids_of(scene, **kw):
    return scene.render(spp=1, aovs=["object_id"], **kw)[1]["object_id"]


def test_boxes_and_areas_by_hand():
    ids = np.full((6, 7), coco.NO_ID, dtype=np.uint32)
    ids[0, 0] = 4  # one pixel in the corner
    ids[2:5, 1:3] = 9
    ids[5, 6] = 9  # the same object, apart: one box around both
    ids[1, 3:7] = 2  # a row to the right edge
    got = coco.instances(ids)
    assert got == [
        {"object_id": 2, "bbox": [3, 1, 4, 1], "area": 4},
        {"object_id": 4, "bbox": [0, 0, 1, 1], "area": 1},
        {"object_id": 9, "bbox": [1, 2, 6, 4], "area": 7},
    ]
    assert coco.instances(np.full((3, 3), coco.NO_ID, dtype=np.uint32)) == []
    fractions = coco.instances(ids, amodal={2: 8, 4: 1, 9: 14})
    assert [g["visible_fraction"] for g in fractions] == [0.5, 1.0, 0.5]
    with pytest.raises(ValueError, match=r"object 9: its amodal area \(5 pixels\) is less"):
        coco.instances(ids, amodal={2: 8, 4: 1, 9: 5})
    with pytest.raises(ValueError, match="uint32 object_id AOV, not a float32 array"):
        coco.instances(ids.astype(np.float32))


def test_boxes_and_areas_of_a_render_are_its_pixels():
    scene = penumbra.load(SCENES / "cornell.toml")
    ids = ids_of(scene, camera="high", width=48, height=36)
    got = coco.instances(ids)
    assert [g["object_id"] for g in got] == sorted(set(ids.ravel().tolist()) - {coco.NO_ID})
    for g in got:
        ys, xs = np.nonzero(ids == g["object_id"])
        x, y, w, h = g["bbox"]
        assert (x, y, x + w - 1, y + h - 1) == (xs.min(), ys.min(), xs.max(), ys.max())
        assert g["area"] == len(xs)
    assert sum(g["area"] for g in got) == int((ids != coco.NO_ID).sum())


def test_camera_rays_are_the_id_aovs_center_rays():
    scene = penumbra.load(SCENES / "cornell.toml")
    camera = scene.camera("left")
    _, aov = scene.render(camera="left", width=20, height=15, spp=1, aovs=["depth", "position"])
    rays = penumbra._core.camera_rays(camera._args(), 20, 15)
    assert rays.shape == (15, 20, 6) and rays.dtype == np.float32
    hit = np.isfinite(aov["depth"])
    along = rays[..., :3] + aov["depth"][..., None] * rays[..., 3:]
    assert hit.sum() > 150
    assert np.allclose(along[hit], aov["position"][hit], atol=1e-4)
    assert np.allclose(np.linalg.norm(rays[..., 3:], axis=-1), 1, atol=1e-6)


def test_the_amodal_area_is_the_objects_area_alone():
    both, wall_alone, ball_alone = scene_of(WALL, BALL), scene_of(WALL), scene_of(dict(BALL))
    ids = ids_of(both)
    amodal = coco.amodal_areas(both, None, 40, 30)
    # Object 0 is the wall, 1 the ball: each one's amodal area is its area rendered alone.
    assert amodal[0] == int((ids_of(wall_alone) == 0).sum())
    assert amodal[1] == int((ids_of(ball_alone) == 0).sum())
    got = {g["object_id"]: g for g in coco.instances(ids, coco.amodal_areas(both, None, 40, 30, ids))}
    assert got[1]["visible_fraction"] == 1.0
    hidden = amodal[0] - got[0]["area"]
    assert 0 < hidden <= got[1]["area"]
    assert got[0]["visible_fraction"] == pytest.approx(got[0]["area"] / amodal[0])
    # Another camera, by explicit Camera or name: the ball in the corner, the wall whole.
    side = penumbra.Camera((3, 0, 5), (0, 0, 0), (0, 1, 0), 40)
    ids = ids_of(both, camera=side)
    fractions = {g["object_id"]: g["visible_fraction"]
                 for g in coco.instances(ids, coco.amodal_areas(both, side, 40, 30, ids))}
    assert fractions[1] == 1.0 and fractions[0] < 1.0
    with pytest.raises(ValueError, match=r"object_id has shape \(30, 40\), not the image's \(20, 40\)"):
        coco.amodal_areas(both, None, 40, 20, ids)


def test_without_pycocotools_annotations_say_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "pycocotools", None)
    monkeypatch.setitem(sys.modules, "pycocotools.mask", None)
    scene = scene_of(WALL)
    with pytest.raises(ImportError, match=r"need pycocotools .*pip install pycocotools"):
        coco.annotations(scene, [{"file_name": "a.png", "object_id": ids_of(scene)}])
    with pytest.raises(ImportError, match="pip install pycocotools"):
        coco.check_available()


# pycocotools' own decode (used here to check the masks; penumbra.coco only encodes) hands
# numpy 2 an object whose __array__ takes no copy keyword: its DeprecationWarning, one per
# decode, is pycocotools' to fix, not a sign of anything wrong here.
@pytest.mark.filterwarnings(
    "ignore:__array__ implementation doesn't accept a copy keyword:DeprecationWarning:"
    r"pycocotools\.mask"
)
def test_rle_masks_decode_to_the_id_aov(tmp_path):
    mask = pytest.importorskip("pycocotools.mask")
    from pycocotools.coco import COCO

    scene = penumbra.load(SCENES / "cornell.toml")
    views = [("high", 48, 36), ("left", 30, 40)]
    images = []
    for name, w, h in views:
        images.append({"file_name": f"{name}.png", "object_id": ids_of(scene, camera=name,
                                                                       width=w, height=h),
                       "camera": name})
    images.append({"file_name": "plain.png", "object_id": images[0]["object_id"]})
    path = tmp_path / "sub" / "annotations.json"
    coco.write_annotations(path, scene, images)
    data = json.loads(path.read_text())
    assert [i["file_name"] for i in data["images"]] == ["high.png", "left.png", "plain.png"]
    assert [c["name"] for c in data["categories"]] == [o["key"] for o in scene.objects]
    assert data["info"]["scene_digest"] == scene.scene_digest
    by_image = {}
    for a in data["annotations"]:
        by_image.setdefault(a["image_id"], []).append(a)
    for k, image in enumerate(images, 1):
        ids = image["object_id"]
        h, w = ids.shape
        listed = by_image[k]
        assert sorted(a["object_id"] for a in listed) == sorted(set(ids.ravel().tolist()) - {coco.NO_ID})
        for a in listed:
            rle = {"size": a["segmentation"]["size"], "counts": a["segmentation"]["counts"].encode()}
            decoded = mask.decode(rle)
            assert decoded.shape == (h, w)
            assert np.array_equal(decoded.astype(bool), ids == a["object_id"])
            assert mask.toBbox(rle).tolist() == a["bbox"] and int(mask.area(rle)) == a["area"]
            entry = scene.objects[a["category_id"] - 1]
            assert entry["ids"][0] <= a["object_id"] < entry["ids"][1]
            assert a["iscrowd"] == 0
            if "camera" in image:
                assert 0 < a["visible_fraction"] <= 1
            else:
                assert "visible_fraction" not in a
    # pycocotools' own reader takes the file.
    api = COCO(str(path))
    assert len(api.getAnnIds()) == len(data["annotations"])
    ann = api.loadAnns(api.getAnnIds(imgIds=[1]))[0]
    assert np.array_equal(api.annToMask(ann).astype(bool), images[0]["object_id"] == ann["object_id"])
