"""Renders split into shards (issue 41): through Dask workers and by hand, merged bit for
bit; scenes pickle (file or text origin, with their update edits)."""

import os
import pickle
from pathlib import Path

import numpy as np
import pytest

import penumbra
from penumbra import distributed

ROOT = Path(__file__).resolve().parents[2]
CBOX = ROOT / "scenes" / "cornell-box.xml"
ARGS = dict(spp=8, seed=3, resolution=(40, 30))


def test_parts_merge_to_the_single_render_bit_for_bit():
    scene = penumbra.load_file(CBOX)
    want = penumbra.render(scene, **ARGS)
    for k in (1, 3, 7):
        parts = [distributed.render_part(scene, i, k, **ARGS) for i in reversed(range(k))]
        assert np.array_equal(distributed.merge(parts), want), f"{k} parts"
    # BDPT too.
    want = penumbra.render(scene, integrator="bdpt", **ARGS)
    parts = [distributed.render_part(scene, i, 3, integrator="bdpt", **ARGS) for i in range(3)]
    assert np.array_equal(distributed.merge(parts), want)


def test_merge_refuses_a_wrong_set():
    scene = penumbra.load_file(CBOX)
    parts = [distributed.render_part(scene, i, 3, **ARGS) for i in range(3)]
    with pytest.raises(ValueError, match="in no state"):
        distributed.merge(parts[:2])
    with pytest.raises(ValueError, match="in both"):
        distributed.merge(parts + parts[1:2])
    other = distributed.render_part(scene, 2, 3, spp=4, seed=3, resolution=(40, 30))
    with pytest.raises(ValueError, match="another render"):
        distributed.merge(parts[:2] + [other])
    with pytest.raises(ValueError, match="cannot be split"):
        distributed.render_part(scene, 0, 2, integrator="sppm", **ARGS)


def test_scenes_pickle_with_their_edits():
    scene = penumbra.load_file(CBOX)
    key = next(k for k, v in scene.parameters().items() if isinstance(v, tuple))
    scene.update({key: (0.2, 0.5, 0.3)})
    copy = pickle.loads(pickle.dumps(scene))
    assert copy.parameters()[key] == scene.parameters()[key]
    assert np.array_equal(penumbra.render(copy, **ARGS), penumbra.render(scene, **ARGS))
    text = penumbra.load_string(CBOX.read_text())
    copy = pickle.loads(pickle.dumps(text))
    assert np.array_equal(penumbra.render(copy, **ARGS), penumbra.render(text, **ARGS))


def test_four_shards_on_a_dask_local_cluster():
    """Acceptance 3 of issue 41: 4 shards through a LocalCluster of 2 worker processes give
    the single process's image bit for bit."""
    if os.environ.get("CI"):
        import distributed as dd  # CI installs it: a missing package is a failure there
    else:
        dd = pytest.importorskip("distributed")
    scene = penumbra.load_file(CBOX)
    scene.update({next(k for k, v in scene.parameters().items() if isinstance(v, tuple)): (0.7, 0.1, 0.1)})
    want = penumbra.render(scene, **ARGS)
    with dd.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                         dashboard_address=None) as cluster, dd.Client(cluster) as client:
        got = distributed.render(scene, shards=4, client=client, threads=1, **ARGS)
        pids = client.run(os.getpid)
    assert len(set(pids.values())) == 2 and os.getpid() not in pids.values()
    assert np.array_equal(got, want)
