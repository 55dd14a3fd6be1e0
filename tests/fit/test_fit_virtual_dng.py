"""The fit of a virtual DNG capture, read through rawpy, agrees with the fit of the image it was made from.

The image is a synthetic bench capture (``tests/fit/synthetic.py``: vissim's own forward chain,
not the fit's model); both it and its no-lens reference go through the virtual camera and the
DNG (``tests/fit/virtual_dng.py``).  The DNG adds shot, read and quantisation noise (about
0.007-0.009 in reflectance on paper: G, R, B) and the per-channel white balance from the paper.  Agreement: in
each power-vector component the two fits differ by less than the DNG fit's 95 % noise
half-width (the DNG's own noise is what separates them), and by less than 0.02 D.
"""

import numpy as np

from vissim.fit.result import Z95
from vissim.fit.rx_fit import fit_rx
from vissim.optics.rx.trial_lens import TrialLens

from tests.fit.synthetic import BENCH, capture
from tests.fit.virtual_dng import through_virtual_dng


def test_a_virtual_dng_capture_fits_as_the_image_it_was_made_from(tmp_path):
    image, reference, truth = capture(TrialLens(1.0, -1.5, 30.0), noise=0.002)
    fits = {}
    for name, (img, ref) in {
        "image": (image, reference),
        "dng": (through_virtual_dng(image, tmp_path / "lens.dng", seed=5),
                through_virtual_dng(reference, tmp_path / "no_lens.dng", seed=6)),
    }.items():
        fits[name] = fit_rx(img, ref, arcmin_per_px=1.0, pupil_diameter_mm=3.6, bench=BENCH)
        assert fits[name].status == "ok", fits[name].reason
    difference = np.subtract(fits["dng"].power_vector, fits["image"].power_vector)
    noise_half_width = Z95 * np.sqrt(np.diag(fits["dng"].best.noise_covariance))
    print(f"DNG - image fit: {np.round(difference, 4)} D; DNG noise half-width {np.round(noise_half_width, 4)} D")
    assert np.all(np.abs(difference) < noise_half_width), (difference, noise_half_width)
    assert np.max(np.abs(difference)) < 0.02
    assert np.max(np.abs(np.subtract(fits["dng"].power_vector, truth))) < 0.03
