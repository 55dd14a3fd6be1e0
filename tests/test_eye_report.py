"""`vissim.optics.eyes.report` and the toric cornea of the exact trace.

Oracles:

* the prescription an eye was made to need (`vissim.optics.eyes.ametropia`: closed-form 4 × 4
  paraxial matrices, no real ray) against the exact trace through its biconic cornea (real rays,
  Zernike fit, paraxial refraction at the 12 mm spectacle plane): within 0.02 D at a 2 mm pupil, at
  oblique axes, which pins the biconic's axis to the TABO frame;
* the diffraction-limited MTF of a circular pupil (Goodman 2005, Eq. 6-32, `diffraction_mtf`,
  closed form): the MTF pipeline on a zero wavefront meets it within 2e-3 in every direction.
"""

import numpy as np
import pytest

from vissim.errors import VissimInputError
from vissim.optics.eyes.fixation import ametropic_eye
from vissim.optics.eyes.eye import build_eye
from vissim.optics.eyes.models import navarro_1985
from vissim.optics.eyes.refraction import eye_refraction
from vissim.optics.eyes.report import eye_mtf, eye_report
from vissim.optics.eyes.surfaces import eye_surfaces
from vissim.optics.eyes.traced_wavefront import trace_eye_wavefront
from vissim.optics.rx.prescription import Prescription
from vissim.optics.psf.metrics import diffraction_mtf
from vissim.optics.raytrace import Biconic, Conic
from vissim.optics.pupil.wavefront import Wavefront

REFRACTION_TOL_D = 0.02
MTF_SAMPLING_TOL = 2e-3


def test_a_toric_cornea_is_traced_as_a_biconic_with_its_tabo_axis():
    eye = ametropic_eye(navarro_1985(), Prescription.parse("-1.00 -2.00 x 30"))
    front = eye_surfaces(eye)[0].shape
    assert isinstance(front, Biconic) and front.axis_deg == 30.0
    assert (front.radius_x_mm, front.radius_y_mm) == (eye.surfaces[0].radius_mm, eye.surfaces[0].radius_y_mm)
    assert front.conic_x == front.conic_y == -0.26
    assert isinstance(eye_surfaces(navarro_1985())[0].shape, Conic)


@pytest.mark.parametrize("text", ["-1.00 -2.00 x 30", "+2.00 -1.50 x 135", "-4.00 -0.75 x 10", "-3.00 DS"])
def test_the_traced_toric_eye_returns_its_prescription(text):
    rx = Prescription.parse(text)
    eye = ametropic_eye(navarro_1985(), rx, 12.0)
    front = trace_eye_wavefront(eye, eye.reference_wavelength_nm, pupil_mm=2.0, samples=33)
    traced = eye_refraction(front, 12.0).paraxial
    got, want = np.array(traced.power_vector()), np.array(rx.power_vector())
    assert np.all(np.abs(got - want) < REFRACTION_TOL_D), (traced, rx)


@pytest.mark.parametrize("field", [(0.0, 0.0), (20.0, 0.0), (10.0, 10.0)])
def test_the_mtf_of_a_perfect_pupil_is_the_diffraction_limit(field):
    frequencies = np.linspace(0.0, 120.0, 25)
    table = eye_mtf(Wavefront.zero(3.0), 550.0, frequencies, field)
    assert set(table) == ({"radial"} if field == (0.0, 0.0) else {"tangential", "sagittal"})
    limit = diffraction_mtf(frequencies, 3.0, 550.0)
    for values in table.values():
        assert values[0] == pytest.approx(1.0, abs=1e-12)
        assert np.max(np.abs(values - limit)) < MTF_SAMPLING_TOL


def test_negative_frequencies_are_refused_naming_the_value():
    with pytest.raises(VissimInputError, match=r"MTF frequency \(per degree\) must be >= 0, got -3"):
        eye_mtf(Wavefront.zero(3.0), 550.0, [1.0, -3.0])
    with pytest.raises(VissimInputError, match="per mm"):
        eye_report(build_eye("navarro-1985", pupil_diameter_mm=3.0), mtf_cyc_per_mm=[-1.0])


def test_a_toric_eyes_power_is_the_mean_of_its_meridians():
    base = navarro_1985()
    sphere = eye_report(build_eye("navarro-1985", pupil_diameter_mm=2.0, rx="-2.00 DS"))
    toric = eye_report(build_eye("navarro-1985", pupil_diameter_mm=2.0, rx="-1.00 -2.00 x 30"))  # the same spherical equivalent
    assert toric.power_diopters == pytest.approx(sphere.power_diopters, abs=1e-9)
    assert base.name == toric.model


def test_lens_surfaces_sit_in_front_of_the_cornea_and_refuse_a_thin_lens():
    import math

    from vissim.optics.eyes.spectacles import lens_surfaces
    from vissim.optics.rx.trial_lens import TrialLens, TrialLensSetup

    lens = TrialLens(-3.0, refractive_index=1.523, center_thickness_mm=1.0)
    front, back = lens_surfaces(TrialLensSetup((lens,), 12.0, math.inf))
    assert (front.vertex_z_mm, back.vertex_z_mm) == (-13.0, -12.0)
    assert front.medium_after(587.56) == pytest.approx(1.523, abs=1e-4) and back.medium_after == 1.0
    # back vertex power F = F1 / (1 - (t/n) F1) with a plano back, so F1 = F / (1 + (t/n) F) (t in m)
    curvature = front.shape.curvature_per_mm[0, 0]
    assert 1000.0 * 0.523 * curvature == pytest.approx(-3.0 / (1.0 - 3.0 * 1e-3 / 1.523), rel=1e-9)
    with pytest.raises(VissimInputError, match="thin"):
        lens_surfaces(TrialLensSetup((TrialLens(-3.0),), 12.0, math.inf))


def test_the_retina_per_degree_through_a_lens_is_the_spectacle_magnification():
    """Spectacle magnification of a thick lens (Bennett & Rabbetts, Clinical Visual Optics, ch. 17):
    SM = 1 / (1 - h P) x 1 / (1 - (t/n) F1), P the back vertex power, h its back vertex to the eye's
    entrance pupil, F1 the front surface's power; without a lens the 4 x 4 path meets the 2 x 2 one."""
    import math

    from vissim.bench.atv.tube import atv_trial_lens
    from vissim.optics.eyes.paraxial import entrance_pupil_position_mm, retinal_mm_per_deg
    from vissim.optics.eyes.spectacles import system_retinal_mm_per_deg
    from vissim.optics.rx.trial_lens import TrialLensSetup

    eye = ametropic_eye(navarro_1985(), Prescription(-3.0))
    wavelength = eye.reference_wavelength_nm
    bare = retinal_mm_per_deg(eye, wavelength)
    assert system_retinal_mm_per_deg(eye, TrialLensSetup((), 12.0, math.inf), wavelength) == pytest.approx(bare,
                                                                                                           rel=1e-12)
    lens = atv_trial_lens(-3.0)
    h_m = (12.0 + entrance_pupil_position_mm(eye, wavelength)) / 1000.0
    front = lens.front_surface_power_matrix()[0][0]
    expected = 1.0 / (1.0 + 3.0 * h_m) / (1.0 - lens.center_thickness_mm / 1000.0 / 1.523 * front)
    through = system_retinal_mm_per_deg(eye, TrialLensSetup((lens,), 12.0, math.inf), wavelength)
    assert through / bare == pytest.approx(expected, rel=1e-4)


def _autocorrelation_mtf(opd_um, pupil_mm: float, wavelength_nm: float, frequencies_cyc_per_deg, samples: int = 1024):
    """Independent oracle: the MTF as the pupil function's normalised autocorrelation (Goodman 2005,
    Eq. 6-29), by FFT on a zero-padded grid; a shift s (mm) in the pupil is the frequency s / λ per radian."""
    step = pupil_mm / samples
    x = (np.arange(samples) - (samples - 1) / 2) * step
    xx, yy = np.meshgrid(x, x)
    inside = np.hypot(xx, yy) <= pupil_mm / 2
    field = np.where(inside, np.exp(2j * np.pi * opd_um(xx, yy) / (wavelength_nm / 1000.0)), 0.0)
    padded = np.zeros((2 * samples, 2 * samples), complex)
    padded[:samples, :samples] = field
    spectrum = np.fft.fft2(padded)
    auto = np.fft.ifft2(spectrum * np.conj(spectrum))  # auto[s] = sum P(x + s) P*(x)
    auto = np.abs(auto) / np.abs(auto[0, 0])
    shifts_mm = np.asarray(frequencies_cyc_per_deg) * 180.0 / np.pi * wavelength_nm * 1e-6
    return np.interp(shifts_mm, np.arange(samples) * step, auto[0, :samples])


def test_a_psf_wider_than_the_first_field_is_computed_over_one_that_holds_it():
    # -8 D over 4 mm blurs to a 55 arcmin radius, beyond the 512 px field's 48 at this sampling
    front = Wavefront.from_prescription(Prescription(-8.0), 4.0)
    frequencies = np.array([0.0, 2.0, 3.0, 5.0, 8.0])
    table = eye_mtf(front, 550.0, frequencies)
    oracle = _autocorrelation_mtf(lambda x, y: front.opd_um(x, y), 4.0, 550.0, frequencies)
    assert np.max(np.abs(table["radial"] - oracle)) < 0.01, (table["radial"], oracle)
