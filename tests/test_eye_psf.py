"""``vissim psf --eye-model``: a schematic eye's PSF from its traced wavefront (issue 26, must-show).

The oracle is tests/fraunhofer_reference.py: direct quadrature of the Fraunhofer integral
(Gauss-Legendre in r, trapezoid in θ, Gauss-Legendre over each pixel), with its own OSA Zernikes;
it shares no code with vissim. Its API takes Zernike coefficients, so it is given the traced
wavefront's OSA fit (orders up to 8 over the entrance pupil), the OPD that `compute_psf` is given
too; that the fit *is* the traced OPD is checked here by the fit's residual (< 1e-3 of a wave
RMS), and the fit itself by tests/test_eye_wavefront.py.

Tolerance: issue 12's, every probed pixel within 2e-3 of the oracle's peak pixel (as the reduced
eye in tests/test_psf_accuracy.py). Measured (float64, about 60 probed pixels each, ``pytest -s`` prints it):
1.1e-6 of the peak at 3 mm and 555 nm, 1.2e-6 at 6 mm and 589.3 nm.
"""

import math

import numpy as np
import pytest
from fraunhofer_reference import pixel_values, probe_pixels

from vissim.cli import main
from vissim.imageio import read_image
from vissim.optics.eyes.eye import build_eye
from vissim.optics.eyes.models import eye_model
from vissim.optics.eyes.psf_wavefront import eye_spectral_wavefront, eye_wavefront
from vissim.optics.eyes.traced_wavefront import trace_eye_wavefront
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.compute import compute_psf
from vissim.optics.pupil.wavefront import Wavefront

#: Issue 12 and 26: every probed pixel within 2e-3 of the oracle's peak pixel.
PEAK_FRACTION = 2e-3


@pytest.mark.parametrize(("pupil_mm", "wavelength_nm", "arcmin_per_px", "size_px"),
                         [(3.0, 555.0, 0.25, 129), (6.0, 589.3, 0.25, 161)])
def test_navarro_psf_matches_the_fraunhofer_quadrature_of_its_traced_wavefront(pupil_mm, wavelength_nm,
                                                                              arcmin_per_px, size_px):
    traced = trace_eye_wavefront(eye_model("navarro-1985"), wavelength_nm, pupil_mm=pupil_mm)
    assert traced.fit_residual_rms_um < 1e-3 * wavelength_nm * 1e-3  # the Zernikes are the traced OPD
    front = eye_wavefront(build_eye("navarro-1985", pupil_diameter_mm=pupil_mm), wavelength_nm=wavelength_nm)
    assert front.coefficients_um[(4, 0)] > 0.0  # the eye's own spherical aberration is there
    psf = compute_psf(front, wavelength_nm=wavelength_nm, arcmin_per_px=arcmin_per_px, size_px=size_px,
                      mode="wave", pixel="integrate", dtype=np.float64)
    values = psf.data * psf.energy_in_field
    pixels = probe_pixels(values, np.random.default_rng(26), n_line=15, n_random=16)
    offsets = pixels - size_px // 2
    oracle = pixel_values(dict(traced.zernike_um), traced.entrance_pupil_mm, pupil_mm, wavelength_nm,
                          arcmin_per_px, offsets, integrate=True)
    error = np.abs(values[pixels[:, 0], pixels[:, 1]] - oracle).max() / oracle.max()
    print(f"navarro-1985 {pupil_mm:g} mm {wavelength_nm:g} nm: max |vissim - oracle| / peak = {error:.2e}")
    assert error <= PEAK_FRACTION


def test_the_lights_vergence_adds_the_reduced_eyes_wavefront_over_the_entrance_pupil():
    """Oracle: an object at vergence V (D) blurs as the reduced eye whose correcting lens is -V (docs/conventions.md,
    "Prescriptions"); the matrix form for a toric vergence (a lens in front)."""
    vergence = -np.asarray(Prescription.parse("-1.50 -0.75 x 30").power_matrix())
    eye = build_eye("navarro-1985", pupil_diameter_mm=4.0)
    own = eye_wavefront(eye, wavelength_nm=589.3)
    both = eye_wavefront(eye, wavelength_nm=589.3, vergence_diopters=vergence)
    reduced = Wavefront.from_prescription(Prescription.parse("-1.50 -0.75 x 30"), 4.0)
    for key in {*own.coefficients_um, *reduced.coefficients_um}:
        expected = own.coefficients_um.get(key, 0.0) + reduced.coefficients_um.get(key, 0.0)
        assert both.coefficients_um.get(key, 0.0) == pytest.approx(expected, abs=1e-12)
    far = eye_wavefront(eye, wavelength_nm=589.3, vergence_diopters=-0.5)  # an object 2 m away: 0.5 D hyperopic blur
    assert (far.coefficients_um[(2, 0)] - own.coefficients_um[(2, 0)]) == pytest.approx(
        -0.5 * 2.0**2 / (4 * math.sqrt(3)), rel=1e-12)


def test_an_eye_with_a_prescription_is_the_ametropic_eye_and_reads_it_back_at_the_spectacle_plane():
    """The eye that has -2.00 -1.00 x 30 at 12 mm is built in closed paraxial form (axial length, toric cornea:
    `ametropia`); its traced front's paraxial refraction (the curvature at the pupil centre, Thibos et al. 2004)
    over a 1 mm pupil, carried from the entrance pupil to the spectacle plane by the vergence transfer
    F' = F (I + d F)^-1, is the prescription to 0.01 D (the order-8 fit of 1 mm leaves < 0.005 D,
    tests/test_eye_wavefront.py). Not the old sum of the emmetropic model's front and the prescription's: that
    eye reads -2.00 -1.00 x 30 at the pupil, not at the spectacles (0.1 D off in M)."""
    from vissim.optics.eyes.paraxial import entrance_pupil_position_mm, mean_meridian_eye
    from vissim.optics.eyes.refraction import paraxial_prescription

    rx = Prescription.parse("-2.00 -1.00 x 30")
    eye = build_eye("navarro-1985", pupil_diameter_mm=1.0, rx=rx, vertex_distance_mm=12.0)
    front = eye_wavefront(eye)
    at_pupil = np.asarray(paraxial_prescription(front.coefficients_um, 1.0).power_matrix())
    distance_m = 1e-3 * (12.0 + entrance_pupil_position_mm(mean_meridian_eye(eye.optics), 589.3))
    at_spectacles = at_pupil @ np.linalg.inv(np.eye(2) + distance_m * at_pupil)
    assert np.abs(at_spectacles - np.asarray(rx.power_matrix())).max() < 0.01


def test_cli_psf_with_an_eye_model_writes_an_image_recording_the_model(capsys, tmp_path):
    target = tmp_path / "eye.exr"
    code = main(["psf", "--eye-model", "navarro-1985", "--rx", "-1.00", "--pupil-mm", "3", "--wavelength-nm", "555",
                 "--arcmin-per-px", "0.5", "--size", "65", "-o", str(target)])
    assert code == 0
    image = read_image(target)
    inputs = image.provenance["inputs"]
    assert inputs["eye_model"] == "navarro-1985"
    assert inputs["eye_wavefront_um"]["4,0"] > 0.0
    assert image.pixels.shape == (65, 65) and float(image.pixels.sum()) == pytest.approx(
        inputs["psf"]["energy_in_field"], rel=1e-4)


@pytest.mark.parametrize("argv", [["--eye-model", "no-such-eye"],
                                  ["--eye-model", "navarro-1985", "--wavelength-nm", "500,600,500"],
                                  ["--eye-model", "navarro-1985", "--lca"]])
def test_cli_psf_eye_model_bad_input_is_one_error_line_and_exit_2(capsys, tmp_path, argv):
    capsys.readouterr()
    code = main(["psf", *argv, "--pupil-mm", "3", "-o", str(tmp_path / "x.exr")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("vissim: error:"), err
    assert not (tmp_path / "x.exr").exists()


def test_cli_psf_eye_model_takes_field_and_accommodation_as_the_library_does(capsys, tmp_path):
    """The CLI's PSF equals compute_psf of the eye's one-wavelength spectral front (eye_wavefront's front with
    its map to visual angle) at the same field and accommodation (float32 file)."""
    target = tmp_path / "off.exr"
    code = main(["psf", "--eye-model", "navarro-1985", "--pupil-mm", "4", "--wavelength-nm", "555", "--field-deg", "10,0",
                 "--accommodation-diopters", "1", "--arcmin-per-px", "0.5", "--size", "65", "-o", str(target)])
    assert code == 0
    eye = build_eye("navarro-1985", pupil_diameter_mm=4.0, accommodation_diopters=1.0)
    front = eye_wavefront(eye, wavelength_nm=555.0, field_deg=(10.0, 0.0))
    assert abs(front.coefficients_um[(2, 2)]) > 1e-3  # off-axis astigmatism is there
    spectral = eye_spectral_wavefront(eye, wavelengths_nm=[555.0], field_deg=(10.0, 0.0))
    assert spectral.fronts[0].coefficients_um == front.coefficients_um and spectral.field_map is not None
    psf = compute_psf(spectral, wavelength_nm=555.0, arcmin_per_px=0.5, size_px=65, normalise="total")
    image = read_image(target)
    assert image.provenance["inputs"]["field_deg"] == "10,0"
    assert np.abs(image.pixels - psf.data).max() <= 1e-5 * psf.data.max()


def test_cli_psf_field_without_an_eye_model_is_one_error_line(capsys, tmp_path):
    capsys.readouterr()
    code = main(["psf", "--rx", "-1", "--field-deg", "5,0", "--pupil-mm", "3", "-o", str(tmp_path / "x.exr")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--eye-model" in err[0], err
