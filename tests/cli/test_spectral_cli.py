"""``vissim psf`` and ``vissim eye`` over several wavelengths or a named spectrum.

The physics of the polychromatic eye (its PSF against direct quadratures, its chromatic defocus and
its transverse chromatic aberration) is pinned in tests/test_eye_spectral.py; here: that the commands
compute what the library computes, record the light they used, and refuse bad input with one line.
"""

import json

import numpy as np
import pytest

from vissim.cli import main
from vissim.imageio import read_image
from vissim.optics.eyes.eye import build_eye
from vissim.optics.eyes.psf_wavefront import eye_spectral_wavefront
from vissim.optics.eyes.report import MtfSpectrum, eye_report
from vissim.optics.psf.compute import compute_psf
from vissim.spectra import named_spectrum


def _error_line(capsys, argv):
    capsys.readouterr()
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("vissim: error:"), err
    return err[0]


@pytest.mark.slow
def test_psf_of_an_eye_model_at_several_wavelengths_is_the_librarys_spectral_psf(tmp_path):
    target = tmp_path / "poly.exr"
    code = main(["psf", "--eye-model", "navarro-1985", "--pupil-mm", "3", "--field-deg", "10,0",
                 "--wavelength-nm", "450,550,650", "--weights", "1,2,1", "--arcmin-per-px", "0.5", "--size", "65",
                 "-o", str(target)])
    assert code == 0
    spectral = eye_spectral_wavefront(build_eye("navarro-1985", pupil_diameter_mm=3.0), wavelengths_nm=(450, 550, 650), field_deg=(10, 0))
    psf = compute_psf(spectral, weights=(1, 2, 1), arcmin_per_px=0.5, size_px=65, normalise="total")
    image = read_image(target)
    inputs = image.provenance["inputs"]
    assert np.abs(image.pixels - psf.data).max() <= 1e-5 * psf.data.max()
    assert inputs["psf"]["wavelengths_nm"] == [450.0, 550.0, 650.0]
    assert inputs["psf"]["weights"] == pytest.approx([0.25, 0.5, 0.25])
    assert inputs["psf"]["wavefront"]["reference_wavelength_nm"] == 589.3
    assert set(inputs["eye_wavefront_um"]) == {"450", "550", "650"}


def test_psf_spectrum_photopic_weights_each_wavelength_by_v(tmp_path):
    target = tmp_path / "photopic.exr"
    assert main(["psf", "--rx", "-0.5", "--pupil-mm", "2", "--spectrum", "photopic", "--arcmin-per-px", "1",
                 "--size", "33", "-o", str(target)]) == 0
    inputs = read_image(target).provenance["inputs"]
    wavelengths, v = named_spectrum("photopic")
    assert inputs["spectrum"] == "photopic"
    assert inputs["psf"]["wavelengths_nm"] == list(wavelengths)
    assert inputs["psf"]["weights"] == pytest.approx([w / sum(v) for w in v])


@pytest.mark.parametrize(("argv", "fragment"), [
    (["--spectrum", "photopic", "--wavelength-nm", "550"], "--spectrum photopic"),
    (["--spectrum", "photopic", "--weights", "1"], "--spectrum photopic"),
    (["--spectrum", "scotopic"], "scotopic"),
    (["--eye-model", "navarro-1985", "--spectrum", "photopic", "--lca"], "--lca"),
    (["--eye-model", "navarro-1985", "--wavelength-nm", "500,500"], "twice"),
    (["--eye-model", "navarro-1985", "--wavelength-nm", "500,600", "--weights", "1"], "weight"),
])
def test_psf_bad_light_is_one_error_line_and_exit_2(capsys, tmp_path, argv, fragment):
    line = _error_line(capsys, ["psf", "--rx", "-1", "--pupil-mm", "3", *argv, "-o", tmp_path / "x.exr"])
    assert fragment in line
    assert not (tmp_path / "x.exr").exists()


@pytest.mark.slow
def test_eye_mtf_over_several_wavelengths_keeps_zernikes_at_the_reference_and_records_the_light(capsys):
    capsys.readouterr()
    code = main(["eye", "--eye-model", "navarro-1985", "--pupil-mm", "3", "--wavelength-nm", "470,555,640", "--weights", "1,2,1",
                 "--mtf-cyc-per-deg", "10,30", "--json"])
    out = capsys.readouterr().out
    assert code == 0
    record = json.loads(out)
    mono = eye_report(build_eye("navarro-1985", pupil_diameter_mm=3.0), mtf_cyc_per_deg=[10, 30])
    poly = eye_report(build_eye("navarro-1985", pupil_diameter_mm=3.0), mtf_cyc_per_deg=[10, 30],
                      mtf_spectrum=MtfSpectrum((470.0, 555.0, 640.0), (1.0, 2.0, 1.0)))
    assert record["wavelength_nm"] == 589.3 and record["zernike_um"] == mono.as_json()["zernike_um"]
    assert record["mtf"]["spectrum"] == {"name": "wavelengths given", "wavelengths_nm": [470.0, 555.0, 640.0],
                                         "weights": [0.25, 0.5, 0.25], "zernikes_and_refraction_at_nm": 589.3,
                                         "tca_reference_nm": 589.3}
    assert record["mtf"]["cyc_per_deg"] == json.loads(json.dumps(poly.as_json()["mtf"]["cyc_per_deg"]))
    # The eye's chromatic defocus lowers the MTF below that of its reference wavelength alone.
    for (_, p), (_, m) in zip(record["mtf"]["cyc_per_deg"]["radial"], mono.as_json()["mtf"]["cyc_per_deg"]["radial"]):
        assert p < m


def test_eye_text_names_the_mtfs_light(capsys):
    capsys.readouterr()
    assert main(["eye", "--eye-model", "navarro-1985", "--pupil-mm", "2", "--wavelength-nm", "500,600", "--mtf-cyc-per-deg", "10"]) == 0
    out = capsys.readouterr().out
    assert "MTF light" in out and "500-600 nm" in out and "at 589.3 nm" in out


@pytest.mark.parametrize(("argv", "fragment"), [
    (["--wavelength-nm", "555", "--weights", "1"], "--weights"),
    (["--wavelength-nm", "500,600", "--spectrum", "photopic"], "--spectrum"),
    (["--spectrum", "scotopic"], "scotopic"),
    (["--wavelength-nm", "500,600", "--weights", "1,-1"], "weight"),
])
def test_eye_bad_light_is_one_error_line_and_exit_2(capsys, argv, fragment):
    assert fragment in _error_line(capsys, ["eye", "--eye-model", "navarro-1985", "--pupil-mm", "3", "--mtf-cyc-per-deg", "10", *argv])


@pytest.mark.slow
def test_eye_spectrum_photopic_json(capsys):
    capsys.readouterr()
    assert main(["eye", "--eye-model", "navarro-1985", "--pupil-mm", "3", "--spectrum", "photopic", "--wavelength-nm", "555",
                 "--mtf-cyc-per-deg", "10", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["wavelength_nm"] == 555.0 and record["mtf"]["spectrum"]["name"] == "photopic"
    assert len(record["mtf"]["spectrum"]["wavelengths_nm"]) == 31
