"""Work shared over threads (vissim.optics.runtime.threads): the same results as one thread, in order, and no
threads inside threads."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from vissim.optics.runtime import threads
from vissim.optics.runtime.threads import map_on_threads, single_threaded_blas, spare_threads, split_evenly


@pytest.fixture
def two_cores(monkeypatch):
    monkeypatch.setattr(threads, "available_cores", lambda: 2)


def test_shares_split_evenly_in_order():
    assert split_evenly(range(7), 2) == [[0, 1, 2, 3], [4, 5, 6]]
    assert [len(s) for s in split_evenly(range(31), 4)] == [8, 8, 7, 8]
    assert sum(split_evenly(range(31), 2), []) == list(range(31))
    assert split_evenly([1], 4) == [[1]] and split_evenly(range(3), 1) == [[0, 1, 2]]


def test_results_come_in_the_shares_order_from_several_threads(two_cores):
    seen = set()

    def work(k):
        seen.add(threading.get_ident())
        time.sleep(0.02 * (5 - k))  # later shares finish first
        return k * k

    assert map_on_threads(work, range(5)) == [0, 1, 4, 9, 16]
    assert len(seen) == 2


def test_inside_a_threaded_block_there_is_one_thread(two_cores):
    assert spare_threads() == 2
    assert map_on_threads(lambda _: spare_threads(), range(2)) == [1, 1]
    with single_threaded_blas():
        assert spare_threads() == 1


def test_a_failure_is_raised_and_shares_not_started_are_dropped(two_cores):
    started = []

    def work(k):
        started.append(k)
        if k == 0:
            raise ValueError("share 0")
        time.sleep(0.05)
        return k

    with pytest.raises(ValueError, match="share 0"):
        map_on_threads(work, range(40))
    assert len(started) < 40


def test_a_polychromatic_wave_psf_on_two_threads_equals_one_thread(monkeypatch):
    from vissim.optics.psf.compute import compute_psf
    from vissim.optics.pupil.wavefront import Wavefront
    from vissim.optics.rx.prescription import Prescription

    front = Wavefront.from_prescription(Prescription.parse("-0.75 -0.50 x 20"), 4.0)
    wavelengths = [450.0, 500.0, 550.0, 600.0, 650.0]
    kwargs = dict(wavelength_nm=wavelengths, weights=[1, 2, 3, 2, 1], arcmin_per_px=0.5, size_px=96,
                  dtype=np.float64, method="mft")
    monkeypatch.setattr(threads, "available_cores", lambda: 1)
    one = compute_psf(front, **kwargs).data
    monkeypatch.setattr(threads, "available_cores", lambda: 2)
    two = compute_psf(front, **kwargs).data
    assert np.abs(two - one).max() <= 1e-13 * one.max()  # the partial sums' order: round-off only
    assert not np.array_equal(one, np.zeros_like(one))
