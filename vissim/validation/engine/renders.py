"""Making the renders a run needs: here, in a process pool, or on a Dask cluster.

Workers return arrays and this process writes them (``renders/<key>.exr``, keyed by
`vissim.validation.engine.keys.render_key`), so a remote cluster needs no shared file system.
"""

from __future__ import annotations

import concurrent.futures
import multiprocessing
from pathlib import Path
from typing import Callable

import numpy as np

from vissim.imageio import write_image
from vissim.progress import Progress, counter
from vissim.provenance import make_provenance
from vissim.validation.engine.keys import render_key, render_path
from vissim.validation.engine.registry import bench_kind

__all__ = ["render_any", "spec_key", "render_file_provenance", "make_renders"]


def spec_key(spec) -> str:
    """The key of a render spec (its bench kind is ``spec.kind``)."""
    return render_key(spec.kind, spec)


def render_any(spec):
    """Render one spec with its bench kind's renderer on this machine (a worker process or a Dask worker)."""
    return bench_kind(spec.kind).render(spec)


def render_file_provenance(spec, result) -> dict:
    """Provenance of a render file: the spec, and what the renderer says it did.

    ``result`` is an array, or an object with ``pixels`` and optionally ``variant``, ``spp``
    (recorded as ``variant``, ``spp_used``) and ``provenance`` (e.g.
    `vissim.render.run.RenderResult`), whose keys win and whose ``inputs`` are merged.
    """
    provenance = make_provenance(render=spec.as_json())
    for attribute, key in (("variant", "variant"), ("spp", "spp_used")):
        if hasattr(result, attribute):
            provenance[key] = getattr(result, attribute)
    for key, value in (getattr(result, "provenance", None) or {}).items():
        if key == "inputs" and isinstance(value, dict):
            provenance["inputs"].update(value)
        else:
            provenance[key] = value
    return provenance


def make_renders(pending: list, run_dir: Path, workers: int, client, render: Callable,
                 progress: Progress | None) -> None:
    """Render ``pending`` specs into ``run_dir/renders``: on a connected Dask ``client``, or locally."""
    def save(spec, result) -> None:
        pixels = np.asarray(getattr(result, "pixels", result), np.float32)
        write_image(render_path(run_dir, spec_key(spec)), pixels, provenance=render_file_provenance(spec, result),
                    overwrite=True)

    advance = counter(progress, "rendering", len(pending))
    if client is not None:
        from distributed import as_completed

        futures = {client.submit(render, spec, pure=False): spec for spec in pending}
        for future in as_completed(futures):
            save(futures[future], future.result())
            advance()
    elif workers > 1 and len(pending) > 1:
        context = multiprocessing.get_context("spawn")  # Dr.Jit state does not survive fork
        with concurrent.futures.ProcessPoolExecutor(max_workers=min(workers, len(pending)),
                                                    mp_context=context) as pool:
            futures = {pool.submit(render, spec): spec for spec in pending}
            for future in concurrent.futures.as_completed(futures):
                save(futures[future], future.result())
                advance()
    else:
        for spec in pending:
            save(spec, render(spec))
            advance()
