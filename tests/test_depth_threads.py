"""The depth blur's threads, window cropping and progress reports change nothing but speed.

Oracles: the same blur computed on one thread, layer after layer (the pooled path must composite
the same layers in the same order: equal to float32 round-off, abs 1e-6 on a [0, 1] image); the
count of non-empty layers the result itself lists (progress); OpenBLAS's own thread count, read
back through its C interface (the BLAS guard); the scheduler's queue, recorded (`in_order`).
"""

from concurrent.futures import Future

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import vissim.optics.depth.depth_map as depth_module
import vissim.optics.depth.composite as composite_module
from vissim.optics.depth.depth_map import blur_depth
from vissim.optics.depth.psfs import in_order
from vissim.optics.rx.prescription import Prescription
from vissim.optics.runtime.threads import _openblas_controls, single_threaded_blas


def ramp_scene(rows=96, cols=160):
    """White noise on a floor from 6 m (top) to 0.4 m (bottom), with a near panel: many layers, occlusion."""
    image = np.random.default_rng(3).random((rows, cols, 3), dtype=np.float32)
    depth_m = np.repeat((1.0 / np.linspace(1 / 6.0, 1 / 0.4, rows))[:, None], cols, axis=1)
    depth_m[30:70, 50:90] = 0.5
    return image, depth_m


EYE = dict(rx=Prescription(-1.5), pupil_diameter_mm=3.0, arcmin_per_px=1.0)


@pytest.mark.parametrize("padding", ["edge", "reflect"])
def test_layers_blurred_on_threads_equal_one_thread(monkeypatch, padding):
    image, depth_m = ramp_scene()
    monkeypatch.setattr(depth_module, "worker_threads", lambda backend: 3)
    pooled = blur_depth(image, depth_m, padding=padding, **EYE)
    monkeypatch.setattr(depth_module, "worker_threads", lambda backend: 1)
    serial = blur_depth(image, depth_m, padding=padding, **EYE)
    assert len(pooled.layers) > 10  # enough layers to be ahead of the compositing
    np.testing.assert_allclose(pooled.image, serial.image, rtol=0, atol=1e-6)


def test_progress_counts_every_layer_once_in_order():
    image, depth_m = ramp_scene()
    calls = []
    result = blur_depth(image, depth_m, progress=lambda *call: calls.append(call), **EYE)
    total = len(result.layers)
    assert [done for _, done, _ in calls] == list(range(1, total + 1))
    assert {(stage, t) for stage, _, t in calls} == {("depth layers", total)}


def test_an_error_in_a_layer_reaches_the_caller(monkeypatch):
    image, depth_m = ramp_scene()
    monkeypatch.setattr(depth_module, "worker_threads", lambda backend: 2)

    def broken(*args, **kwargs):
        raise RuntimeError("layer failed")

    monkeypatch.setattr(composite_module, "extended_layer", broken)
    with pytest.raises(RuntimeError, match="layer failed"):
        blur_depth(image, depth_m, **EYE)


@pytest.mark.skipif(not _openblas_controls(), reason="no OpenBLAS found among the loaded libraries")
def test_blas_runs_on_one_thread_inside_the_guard_and_as_before_after_it():
    _, get = _openblas_controls()[0]
    before = get()
    with single_threaded_blas():
        with single_threaded_blas():  # nested: still one, and the outer block restores
            assert get() == 1
        assert get() == 1
    assert get() == before


class _RecordingPool:
    """Runs each task as it is queued, and records what was queued at which step of the caller's loop."""

    def __init__(self):
        self.log, self.step = [], 0

    def submit(self, function, *args):
        self.log.append(("layer", args[0], self.step))
        future = Future()
        future.set_result(function(*args))
        return future


class _RecordingOptics:
    def __init__(self, pool):
        self.pool = pool

    def prefetch(self, pool, k):
        if not any(entry[:2] == ("psf", k) for entry in self.pool.log):
            self.pool.log.append(("psf", k, self.pool.step))


@settings(max_examples=200, deadline=None)
@given(n=st.integers(1, 40), threads=st.integers(2, 4), costs=st.lists(st.integers(0, 9), min_size=40, max_size=40),
       with_cost=st.booleans())
def test_in_order_yields_each_layer_once_in_order_and_queues_the_last_ones_largest_first(n, threads, costs, with_cost):
    order = list(range(n))[::-1]  # near to far, as blur_depth asks
    pool = _RecordingPool()
    optics = _RecordingOptics(pool)
    results = []
    for step, item in enumerate(in_order(lambda k: 10 * k, optics, order, pool, threads,
                                         cost=costs.__getitem__ if with_cost else None)):
        results.append(item)
        pool.step = step + 1
    assert results == [(k, 10 * k) for k in order]
    queued = [(k, step) for kind, k, step in pool.log if kind == "layer"]
    assert sorted(k for k, _ in queued) == sorted(order)  # each layer once
    assert [kind for kind, _, _ in pool.log[:2]] == ["psf", "layer"]  # the first layer starts after its PSF alone
    for k in order:  # a layer's PSF is asked for before the layer is queued (no task waits on one queued later)
        assert pool.log.index(next(e for e in pool.log if e[:2] == ("psf", k))) < \
            pool.log.index(next(e for e in pool.log if e[:2] == ("layer", k)))
    # with costs, from this step on (everything left within the PSFs' reach) the rest is queued at once
    final = max(n - (4 * threads + 1), 0) if with_cost else n
    for k, step in queued:
        if step < final:  # before: in order, at most 2 threads + 1 layers ahead of the caller
            assert order.index(k) <= step + 2 * threads
    assert [k for k, step in queued if step < final] == [k for k in order if (k, final) not in queued]
    if with_cost:
        last = [k for k, step in queued if step == final]
        assert last == sorted(last, key=costs.__getitem__, reverse=True)
        assert all(step <= final for _, step in queued)
