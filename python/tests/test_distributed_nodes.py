"""penumbra.distributed on a Ray cluster of several nodes on this machine
(ray.cluster_utils.Cluster): a head node without CPUs, where this driver runs, and two worker
nodes of one CPU each. Every task runs on a node other than the driver's, which shares nothing
with it but Ray's object store, and the results are still the single-process bytes."""

from __future__ import annotations

from pathlib import Path

import pytest

import ray_env

ray = ray_env.ray

import penumbra  # noqa: E402
from penumbra import distributed, views  # noqa: E402

from conftest import SCENES, same_bits  # noqa: E402


@pytest.fixture(scope="module")
def nodes():
    from ray.cluster_utils import Cluster

    cluster = Cluster(
        initialize_head=True,
        head_node_args={"num_cpus": 0, "include_dashboard": False},
    )
    cluster.add_node(num_cpus=1)
    cluster.add_node(num_cpus=1)
    cluster.wait_for_nodes()
    ray.init(address=cluster.address, log_to_driver=False)
    yield cluster
    ray.shutdown()
    cluster.shutdown()


def test_worker_nodes_render_a_frame_and_views_exactly(nodes, tmp_path):
    assert len([n for n in ray.nodes() if n["Alive"]]) == 3
    head = ray.get_runtime_context().get_node_id()
    scene = penumbra.load(SCENES / "showcase.toml", allow_paths=[SCENES.parent / "assets"])
    kw = dict(width=48, height=36, spp=4)
    image = distributed.render_frame(scene, tiles=8, **kw)
    assert same_bits(image, scene.render(**kw))

    batch = views.orbit(center=(0, 1, 0), radius=5, height=1, frames=8, fov=40)
    summary = distributed.render_views(scene, batch, output=str(tmp_path / "{name}.png"), **kw)
    # Which worker node takes a task is the scheduler's choice; never the driver's node.
    assert head not in {r["node"] for r in summary}
    # One build per worker process, on whichever node it is.
    assert sum(r["built"] for r in summary) <= len({r["pid"] for r in summary})
    for v, r in zip(batch, summary):
        expected = tmp_path / "expected.png"
        penumbra.write_image(expected, scene.render(camera=v["camera"], **kw))
        assert Path(r["path"]).read_bytes() == expected.read_bytes(), r["name"]
