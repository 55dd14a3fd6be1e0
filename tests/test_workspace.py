"""Scratch arrays: reused by name, shape and dtype within a thread; never shared across threads;
large ones not kept (memory returned after a big PSF)."""

import threading

import numpy as np

from vissim.optics.runtime import workspace
from vissim.optics.runtime.workspace import scratch


def test_same_request_reuses_the_array_and_others_do_not():
    a = scratch("test_a", (8, 8), np.float32)
    assert scratch("test_a", (8, 8), np.float32) is a
    assert scratch("test_a", (8, 8), np.float64) is not a
    assert scratch("test_a", (8, 9), np.float32) is not a
    assert scratch("test_b", (8, 8), np.float32) is not a


def test_threads_get_their_own_arrays():
    mine = scratch("test_thread", (4,), np.float64)
    theirs = []
    worker = threading.Thread(target=lambda: theirs.append(scratch("test_thread", (4,), np.float64)))
    worker.start()
    worker.join()
    assert theirs[0] is not mine


def test_arrays_over_the_limit_are_not_kept(monkeypatch):
    monkeypatch.setattr(workspace, "MAX_KEPT_BYTES", 1024)
    small = scratch("test_size", (16,), np.float64)  # 128 bytes
    assert scratch("test_size", (16,), np.float64) is small
    big = scratch("test_size", (256,), np.float64)  # 2048 bytes
    assert scratch("test_size", (256,), np.float64) is not big


def test_a_psf_is_not_overwritten_by_the_next():
    # compute_psf's matrix transform runs on scratch arrays; what it returns must be its own.
    import vissim

    first = vissim.compute_psf(vissim.Wavefront.from_prescription(vissim.Prescription(-1.0), 3.0),
                               arcmin_per_px=1.0, size_px=64, method="mft")
    kept = first.data.copy()
    vissim.compute_psf(vissim.Wavefront.from_prescription(vissim.Prescription(-2.0, -1.0, 45.0), 3.0),
                       arcmin_per_px=1.0, size_px=64, method="mft")
    np.testing.assert_array_equal(first.data, kept)
