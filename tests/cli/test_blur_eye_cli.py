"""``vissim blur --eye-model`` and ``vissim blur-depth --eye-model``: results, records and bad input.

Oracles: the traced eye's own dispersion (Navarro's media) against the reduced eye's in-focus
reference (an RGB point blurred at 610/550/465 nm by a Navarro eye focused for the middle of the
spectrum: the blue spot, 1 D out of focus by the eye's LCA, spreads most); the Python API
`vissim.blur_eye` for the same call (plumbing); the recorded provenance.
"""

import numpy as np
import pytest

import vissim
from vissim.cli import main
from vissim.imageio import read_image, write_image

MODEL = "navarro-1985"


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_error_line(code, err, *fragments):
    assert code == 2, err
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("vissim: error: "), err
    for fragment in fragments:
        assert fragment in lines[0], err


@pytest.fixture
def chart(tmp_path):
    path = tmp_path / "in.exr"
    image = np.full((40, 48), 0.8, np.float32)
    image[10:30, 20:26] = 0.05
    write_image(path, image, provenance={"inputs": {"arcmin_per_px": 1.0}})
    return path, image


def test_blur_with_an_eye_model_equals_blur_eye_and_records_the_eye(capsys, tmp_path, chart):
    source, image = chart
    target = tmp_path / "out.exr"
    code, out, err = run(capsys, "blur", source, "-o", target, "--eye-model", MODEL, "--pupil-mm", "3",
                         "--wavelength-nm", "555", "--field-deg", "5,0", "--field-step-deg", "0.7")
    assert code == 0, err
    blurred = read_image(target)
    expected = vissim.blur_eye(image, vissim.build_eye(MODEL, pupil_diameter_mm=3.0), arcmin_per_px=1.0, wavelength_nm=555.0,
                               field_deg=(5.0, 0.0), field_step_deg=0.7)
    np.testing.assert_allclose(blurred.pixels, expected, atol=1e-6)
    eye = blurred.provenance["inputs"]["eye_model"]
    assert eye["model"] == MODEL and eye["field_deg"] == [5.0, 0.0] and eye["field_step_deg"] == 0.7
    assert eye["nodes"] == [1, 3] and eye["node_count"] == 3  # 39 x 47 arcmin spans against a 42 arcmin step
    assert "1 x 3 PSF nodes" in out


def test_an_rgb_point_through_a_navarro_eye_spreads_most_in_the_blue(capsys, tmp_path):
    source, target = tmp_path / "rgb.exr", tmp_path / "rgb_out.exr"
    rgb = np.zeros((41, 41, 3), np.float32)
    rgb[20, 20] = 1.0
    write_image(source, rgb, provenance={"inputs": {"arcmin_per_px": 0.5}})
    code, _, err = run(capsys, "blur", source, "-o", target, "--eye-model", MODEL, "--pupil-mm", "3",
                       "--padding", "constant")
    assert code == 0, err
    out = read_image(target).pixels
    assert out[20, 20, 2] < 0.5 * min(out[20, 20, 0], out[20, 20, 1])  # blue defocused by the eye's own LCA
    assert read_image(target).provenance["inputs"]["eye_model"]["channel_wavelengths_nm"] == [[610.0], [550.0], [465.0]]


@pytest.mark.slow  # 5 s: 3 bands x 7 wavelengths traced
def test_channel_bands_with_an_eye_model_equal_blur_eye_over_the_same_bands(capsys, tmp_path):
    """--channel-fwhm-nm with --eye-model: each channel a Gaussian band (`gaussian_band`), traced at each
    wavelength, as `vissim.blur_eye` with the same bands and weights (plumbing)."""
    from vissim.optics.rx.chromatic import gaussian_band

    source, target = tmp_path / "rgb.exr", tmp_path / "out.exr"
    rgb = np.zeros((41, 41, 3), np.float32)
    rgb[20, 20] = 1.0
    write_image(source, rgb, provenance={"inputs": {"arcmin_per_px": 0.5}})
    code, _, err = run(capsys, "blur", source, "-o", target, "--eye-model", MODEL, "--pupil-mm", "3",
                       "--padding", "constant", "--channel-fwhm-nm", "40")
    assert code == 0, err
    bands = [gaussian_band(w, 40.0) for w in (610.0, 550.0, 465.0)]
    expected = vissim.blur_eye(rgb, vissim.build_eye(MODEL, pupil_diameter_mm=3.0), arcmin_per_px=0.5,
                               wavelength_nm=[b[0] for b in bands], weights=[b[1] for b in bands], background=0.0)
    np.testing.assert_allclose(read_image(target).pixels, expected, atol=1e-6)
    assert len(read_image(target).provenance["inputs"]["eye_model"]["channel_wavelengths_nm"][0]) == len(bands[0][0])


@pytest.mark.parametrize("extra, fragments", [
    (["--lca"], ["--lca", "own dispersion"]),
    (["--channel-fwhm-nm", "20", "--wavelength-nm", "550,600"], ["--channel-fwhm-nm", "one centre wavelength"]),
    (["--field-deg", "95,0"], ["95", "deg"]),
    (["--field-step-deg", "0"], ["--field-step-deg", "degrees"]),
    (["--accommodation-diopters", "12"], ["12"]),
    (["--zernike", "4,0=0.1"], ["--zernike"]),
    (["--device", "cuda"], ["--device cuda", "cpu"]),
])
def test_bad_eye_blur_input_is_one_error_line(capsys, tmp_path, chart, extra, fragments):
    source, _ = chart
    code, _, err = run(capsys, "blur", source, "-o", tmp_path / "o.exr", "--eye-model", MODEL, "--pupil-mm", "3",
                       *extra)
    assert_one_error_line(code, err, *fragments)


def test_eye_options_without_an_eye_model_and_unknown_models_are_refused(capsys, tmp_path, chart):
    source, _ = chart
    code, _, err = run(capsys, "blur", source, "-o", tmp_path / "o.exr", "--rx", "-1", "--pupil-mm", "3",
                       "--field-step-deg", "1")
    assert_one_error_line(code, err, "--field-step-deg", "--eye-model")
    code, _, err = run(capsys, "blur", source, "-o", tmp_path / "o.exr", "--eye-model", "cyclops", "--pupil-mm", "3")
    assert_one_error_line(code, err, "cyclops", "choose from")


@pytest.fixture
def depth_scene(tmp_path):
    image, depth = tmp_path / "aif.exr", tmp_path / "depth.npy"
    pixels = np.full((32, 32), 0.7, np.float32)
    pixels[8:24, 14:18] = 0.05
    write_image(image, pixels, provenance={"inputs": {"arcmin_per_px": 1.0}})
    np.save(depth, np.full((32, 32), 0.5))
    return image, depth


def test_blur_depth_with_an_eye_model_focuses_where_its_traced_wavefront_says(capsys, tmp_path, depth_scene):
    image, depth = depth_scene
    target = tmp_path / "out.exr"
    code, out, err = run(capsys, "blur-depth", image, depth, "-o", target, "--rx", "plano", "--pupil-mm", "3",
                         "--eye-model", MODEL, "--accommodation-diopters", "2", "--wavelength-nm", "555")
    assert code == 0, err
    focus = read_image(target).provenance["inputs"]["focus"]
    assert focus["model"] == MODEL and focus["accommodation_diopters"] == 2.0
    assert 1.8 < focus["in_focus_proximity_diopters"] < 3.0  # a 0.5 m scene near focus (test_eye_field_blur.py)


@pytest.mark.parametrize("extra, fragments", [
    (["--eye-model", MODEL, "--age", "30"], ["--age", "--accommodation-diopters"]),
    (["--eye-model", MODEL, "--accommodation-diopters", "11"], ["11"]),
    (["--eye-model", "cyclops"], ["cyclops"]),
    (["--field-deg", "3,0"], ["--field-deg", "--eye-model"]),
])
def test_bad_eye_blur_depth_input_is_one_error_line(capsys, tmp_path, depth_scene, extra, fragments):
    image, depth = depth_scene
    code, _, err = run(capsys, "blur-depth", image, depth, "-o", tmp_path / "o.exr", "--rx", "plano", "--pupil-mm",
                       "3", *extra)
    assert_one_error_line(code, err, *fragments)
