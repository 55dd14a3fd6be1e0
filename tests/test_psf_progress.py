"""A wave PSF reports its stages through ``progress(stage, done, total)`` (vissim.progress), for either transform.

Oracle: the stages the computation has -- the pupil grid (once for the matrix transform, per
wavelength for the FFT), each wavelength's pupil and transform, the output pixels -- counted
1, 2, ... total, and the PSF unchanged by reporting.  Nothing is timed.
"""

import numpy as np
import pytest

from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf
from vissim.optics.pupil.wavefront import Wavefront


@pytest.mark.parametrize("method, stages", [("mft", 2 * 2 + 2), ("fft", 2 * 2 + 1)])
def test_wave_psf_reports_each_stage_once_in_order(method, stages):
    front = Wavefront.from_prescription(Prescription(-1.0), 3.0)
    kwargs = dict(arcmin_per_px=1.0, size_px=45, wavelength_nm=[610.0, 550.0], method=method)
    calls = []
    psf = compute_psf(front, progress=lambda *call: calls.append(call), **kwargs)
    assert calls == [("wave PSF", done, stages) for done in range(1, stages + 1)]
    np.testing.assert_array_equal(psf.data, compute_psf(front, **kwargs).data)
