"""The rx, psf, blur and demo commands, as a user runs them."""

import json
import logging

import numpy as np
import pytest

from vissim.cli import main
from vissim.imageio import read_image, write_image
from vissim.optics.runtime.array_backend import cuda_available
from vissim.optics.blur.device import blur_image_on


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_rx_json_shape(capsys):
    code, out, _ = run(capsys, "rx", "-2.00/-1.25x180", "--pupil-mm", "6", "--json")
    assert code == 0
    info = json.loads(out)
    assert info["sphere_diopters"] == -2.0 and info["cylinder_diopters"] == -1.25 and info["axis_deg"] == 180
    assert info["spherical_equivalent_diopters"] == pytest.approx(-2.625)
    assert info["M_diopters"] == pytest.approx(-2.625) and info["J0_diopters"] == pytest.approx(0.625)
    assert info["J45_diopters"] == pytest.approx(0.0)
    assert set(info["zernike_um"]) == {"2,-2", "2,0", "2,2"}
    assert info["zernike_um"]["2,0"] > 0  # a myope
    assert info["written"] == []  # --json's shared shape: the files written (none here)


def test_rx_plus_cylinder_is_reported_in_minus_cylinder(capsys):
    _, out, _ = run(capsys, "rx", "+0.50 +1.00 x 90", "--json")
    info = json.loads(out)
    assert (info["sphere_diopters"], info["cylinder_diopters"], info["axis_deg"]) == (1.5, -1.0, 180.0)


@pytest.mark.parametrize("bad", ["-2.00 -1.25 x 200", "-2.00 -1.25", "abc"])
def test_rx_bad_input_is_one_line_and_exit_2(capsys, bad):
    code, out, err = run(capsys, "rx", bad)
    assert code == 2 and out == ""
    assert err.startswith("vissim: error:") and err.count("\n") == 1


def test_psf_writes_a_y_exr_summing_to_its_recorded_energy_in_field(capsys, tmp_path):
    target = tmp_path / "psf.exr"
    code, out, _ = run(capsys, "psf", "--rx", "-1.00 DS", "--pupil-mm", "3", "--arcmin-per-px", "0.5", "--size", "64", "-o", str(target))
    assert code == 0 and "wrote" in out and "PSF 64 × 64 px at 0.5 arcmin/px" in out
    image = read_image(target)
    assert image.channel_names == ("Y",) and image.pixels.dtype == np.float32
    psf_info = image.provenance["inputs"]["psf"]
    assert psf_info["normalisation"] == "total" and 0.99 < psf_info["energy_in_field"] < 1.0
    assert float(image.pixels.sum(dtype=np.float64)) == pytest.approx(psf_info["energy_in_field"], rel=1e-5)
    assert psf_info["arcmin_per_px"] == 0.5 and psf_info["pupil_diameter_mm"] == 3.0
    # refuses to overwrite
    code, _, err = run(capsys, "psf", "--rx", "-1.00 DS", "--pupil-mm", "3", "--size", "64", "--arcmin-per-px", "0.5", "-o", str(target))
    assert code == 2 and "already exists" in err


def test_psf_png_preview_and_zernike_with_prescription_terms(capsys, tmp_path):
    target = tmp_path / "psf.png"
    code, _, _ = run(
        capsys, "psf", "--zernike", "2,0=0.2;2,2=-0.1;4,0=0.05", "--pupil-mm", "3", "--size", "64",
        "--arcmin-per-px", "0.5", "--mode", "geometric", "-o", str(target),
    )
    assert code == 0 and target.exists() and (tmp_path / "psf.exr").exists()


@pytest.mark.parametrize("rx", ["+0.00 DS", "plano"])
def test_psf_of_no_aberration(capsys, tmp_path, rx):
    code, _, _ = run(capsys, "psf", "--rx", rx, "--pupil-mm", "3", "--size", "128", "-o", str(tmp_path / "a.exr"))
    assert code == 0


def test_psf_of_a_field_smaller_than_the_blur_is_written_with_one_warning(capsys, caplog, tmp_path):
    # The field holds 19 % of a -4 D, 6 mm PSF (blur radius 41'): an image of what it holds.
    target = tmp_path / "a.exr"
    with caplog.at_level(logging.WARNING):  # the CLI shows it as one 'vissim: WARNING:' line
        code, out, _ = run(capsys, "psf", "--rx", "-4 DS", "--pupil-mm", "6", "--size", "32", "--arcmin-per-px", "1",
                           "-o", str(target))
    assert code == 0 and "19.23 % of the energy in the field" in out
    assert [r.getMessage().split(";")[0] for r in caplog.records if r.levelno >= logging.WARNING] == [
        "80.8 % of the PSF's energy falls outside the 32 px field (32 arcmin)"]
    energy = read_image(target).provenance["inputs"]["psf"]["energy_in_field"]
    assert float(read_image(target).pixels.sum(dtype=np.float64)) == pytest.approx(energy, rel=1e-5)


def test_blur_uses_the_sampling_in_the_image_provenance(capsys, tmp_path):
    source = tmp_path / "in.exr"
    image = np.full((64, 64), 0.9, np.float32)
    image[20:44, 28:36] = 0.04
    write_image(source, image, provenance={"inputs": {"arcmin_per_px": 1.0}})
    target = tmp_path / "out.exr"
    code, _, _ = run(capsys, "blur", str(source), "-o", str(target), "--rx", "-2.00 DS", "--pupil-mm", "3")
    assert code == 0
    blurred = read_image(target).pixels
    assert float(blurred.mean()) == pytest.approx(float(image.mean()), rel=1e-5)
    assert blurred[32, 24] < 0.9 - 0.05  # light spread into the bar's surround
    # without a sampling anywhere: a clear error
    bare = tmp_path / "bare.exr"
    write_image(bare, image)
    code, _, err = run(capsys, "blur", str(bare), "-o", str(tmp_path / "x.exr"), "--rx", "-2 DS", "--pupil-mm", "3")
    assert code == 2 and "--arcmin-per-px" in err


def test_blur_rgb_with_channel_wavelengths_and_lca(capsys, tmp_path):
    source = tmp_path / "rgb.exr"
    rgb = np.zeros((48, 48, 3), np.float32)
    rgb[24, 24] = 1.0
    write_image(source, rgb)
    target = tmp_path / "rgb_out.exr"
    code, _, _ = run(
        capsys, "blur", str(source), "-o", str(target), "--rx", "plano", "--pupil-mm", "3",
        "--arcmin-per-px", "0.5", "--channels-nm", "610,550,465", "--lca",
    )
    assert code == 0
    out = read_image(target).pixels
    # The eye is in focus for green: the green spot is the most compact.
    assert out[24, 24, 1] > out[24, 24, 0] and out[24, 24, 1] > out[24, 24, 2]


def test_demo_writes_its_files(capsys, tmp_path):
    code, out, _ = run(capsys, "demo", "-o", str(tmp_path / "demo"))
    assert code == 0
    summary = json.loads((tmp_path / "demo" / "summary.json").read_text())
    for case in summary["cases"].values():
        assert case["mean_after"] == pytest.approx(case["mean_before"], rel=1e-5)
    assert (tmp_path / "demo" / "chart_astigmatism.png").exists()


def test_every_command_has_help(capsys):
    for command in ("rx", "trial-lens", "psf", "blur", "demo", "chart"):
        assert main([command, "--help"]) == 0
        assert "usage" in capsys.readouterr().out


def test_blur_with_spectral_bands_per_channel(capsys, tmp_path):
    source = tmp_path / "rgb.exr"
    rgb = np.zeros((48, 48, 3), np.float32)
    rgb[24, 24] = 1.0
    write_image(source, rgb)
    code, _, _ = run(
        capsys, "blur", str(source), "-o", str(tmp_path / "o.exr"), "--rx", "plano", "--pupil-mm", "3",
        "--arcmin-per-px", "0.5", "--channel-fwhm-nm", "40", "--lca",
    )
    assert code == 0
    info = read_image(tmp_path / "o.exr").provenance["inputs"]["psfs"]
    assert len(info) == 3 and all(len(p["wavelengths_nm"]) == 7 for p in info)


@pytest.mark.skipif(cuda_available(), reason="auto would run on the GPU: tests/test_array_backend.py compares that")
def test_blur_on_device_auto_without_a_gpu_runs_the_device_code_and_equals_the_cpu_blur(capsys, tmp_path, monkeypatch):
    import vissim.optics.blur.device as device_module  # the command imports it when it blurs

    source = tmp_path / "rgb.exr"
    rgb = np.full((40, 56, 3), 0.8, np.float32)
    rgb[12:28, 20:30] = (0.05, 0.1, 0.2)
    write_image(source, rgb, provenance={"inputs": {"arcmin_per_px": 1.0}})
    calls = []
    monkeypatch.setattr(device_module, "blur_image_on",
                        lambda *a, **k: calls.append(k["device"]) or blur_image_on(*a, **k))
    outputs = {}
    for device in ("cpu", "auto"):
        target = tmp_path / f"{device}.exr"
        code, _, _ = run(capsys, "blur", str(source), "-o", str(target), "--rx", "-1.50 -1.00 x 30",
                         "--pupil-mm", "3", "--device", device)
        assert code == 0
        outputs[device] = read_image(target)
    assert calls == ["auto"]  # cpu stays on blur_image's path
    assert outputs["auto"].provenance["inputs"]["device"] == "auto"
    np.testing.assert_allclose(outputs["auto"].pixels, outputs["cpu"].pixels, atol=1e-5)


@pytest.mark.skipif(cuda_available(), reason="a GPU is present")
def test_blur_on_cuda_without_a_gpu_is_one_error_line(capsys, tmp_path):
    source = tmp_path / "in.exr"
    write_image(source, np.full((32, 32), 0.5, np.float32), provenance={"inputs": {"arcmin_per_px": 1.0}})
    code, _, err = run(capsys, "blur", str(source), "-o", str(tmp_path / "out.exr"), "--rx", "-1", "--pupil-mm", "3",
                       "--device", "cuda")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "device 'cuda'" in err
    assert not (tmp_path / "out.exr").exists()
