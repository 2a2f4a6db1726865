"""Render one scene over a Dask cluster, merged bit for bit.

``render(scene, shards=K, client=client)`` splits the render's work into ``K`` parts (the
CLI's ``--shard I/K``), renders each on a Dask worker and merges their film states on the
client: the image equals ``penumbra.render(scene, ...)`` with the same arguments, bit for
bit, whichever workers rendered which part and in which order. The scene travels to the
workers pickled (its file path or text, parameters and ``update`` edits), so a scene file
must be at the same path on every worker (a shared file system, or a LocalCluster).

Integrators whose passes depend on each other (sppm/ppm, ptracer, mlt, photon) cannot be
split and raise ``ValueError``. Requires ``dask.distributed`` (``pip install "dask[distributed]"``).
"""

from __future__ import annotations

from typing import Any, List, Optional, Tuple

import numpy as np

from . import _penumbra
from . import _image, _native_render
from ._penumbra import Scene

__all__ = ["render", "render_part", "merge"]


def render_part(
    scene: Scene,
    index: int,
    shards: int,
    spp: Optional[int] = None,
    seed: Optional[int] = 0,
    resolution: Optional[Tuple[int, int]] = None,
    integrator: Optional[str] = None,
    threads: Optional[int] = None,
    sensor: int = 0,
    mode: Optional[str] = None,
) -> bytes:
    """Render part ``index`` of ``shards`` of ``scene`` and return its film state (bytes):
    what a worker runs. Arguments as :func:`penumbra.render`."""
    state = _native_render(
        scene, spp, seed, resolution, integrator, threads, sensor, mode,
        shard=(int(index), int(shards)),
    )[5]
    return bytes(state)


def merge(parts: List[bytes]) -> np.ndarray:
    """The image (float32, height × width × 3) of the film states of all parts of a render.
    Raises ``ValueError`` when they belong to different renders or a part is missing or
    doubled."""
    buf, width, height, _spp = _penumbra.merge_states([bytes(p) for p in parts])
    return _image(buf, width, height)


def render(
    scene: Scene,
    shards: int,
    client: Any = None,
    spp: Optional[int] = None,
    seed: Optional[int] = 0,
    resolution: Optional[Tuple[int, int]] = None,
    integrator: Optional[str] = None,
    threads: Optional[int] = None,
    *,
    sensor: int = 0,
    mode: Optional[str] = None,
) -> np.ndarray:
    """Render ``scene`` as ``shards`` parts on the Dask ``client``'s workers (default: the
    current client, ``distributed.get_client()``) and merge them here. ``threads`` is per
    worker task (default: all cores of the worker). Returns the image
    :func:`penumbra.render` returns for the same arguments, bit for bit."""
    if shards < 1:
        raise ValueError(f"shards must be at least 1, found {shards}")
    if client is None:
        from distributed import get_client

        client = get_client()
    kwargs = dict(
        spp=spp,
        seed=seed,
        resolution=resolution,
        integrator=integrator,
        threads=threads,
        sensor=sensor,
        mode=mode,
    )
    futures = [
        client.submit(render_part, scene, i, shards, pure=False, **kwargs)
        for i in range(shards)
    ]
    return merge(client.gather(futures))
