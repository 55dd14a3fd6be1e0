"""Inputs that used to run for minutes, or to give a number silently, are refused before any work: one
``vissim: error:`` line naming the value and its unit, exit 2, nothing written.

Each case was found accepted (or hanging) by a new user's sweep of bad inputs: an eye campaign made to need
-40 D rendered, then held 3.5 GB for 400 s; a field step of 0.001 deg ran until killed; an eye traced at 200 nm
gave a 290 D myope; a two-letter "letter", an empty sweep and a Zernike pupil without Zernikes were taken
silently; an observer who never saw the display was reported with a threshold of 0.9996.
"""

from __future__ import annotations

import numpy as np
import pytest

from vissim.cli import main
from vissim.imageio import write_image

EYE_CAMPAIGN = """
[campaign]
kind = "eye"
name = "refused"
spp = 4
size_px = [16, 16]
arcmin_per_px = 1.0
{body}
"""


def _refused(capsys, argv, *, says: str, outputs=()):
    code = main(list(argv))
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("vissim: error: "), err
    assert says in lines[0], lines[0]
    assert "Traceback" not in err and out == ""
    for path in outputs:
        assert not path.exists(), path


@pytest.fixture
def grey_image(tmp_path):
    path = tmp_path / "grey.exr"
    write_image(path, np.full((48, 48), 0.5, np.float32), provenance={"inputs": {"arcmin_per_px": 1.0}})
    return path


@pytest.mark.parametrize("argv, says", [
    (["eye", "--eye-model", "navarro-1985", "--pupil-mm", "3", "--wavelength-nm", "200"], "within 365-1014 nm"),
    (["eye", "--eye-model", "navarro-1985", "--pupil-mm", "3", "--rx", "-40"], "-40.00 DS an eye is made to need must be within -30 to 30 dioptres"),
    (["eye", "--eye-model", "navarro-1985", "--pupil-mm", "3", "--rx", "-28 -4 x 90"], "got -32 dioptres"),
    (["eye", "--eye-model", "navarro-1985", "--iris-mm", "9.5"], "iris 9.5 mm gives a 10.2 mm entrance pupil, wider "
                                                                 "than a human eye's 10 mm"),
])
def test_an_eye_outside_its_media_or_its_lenses_is_refused(capsys, argv, says):
    _refused(capsys, argv, says=says)


@pytest.mark.parametrize("option, says", [(["--vertex-mm", "500", "--correction", "-1"], "--vertex-mm must be within"),
                                          (["--correction", "accommodating", "--accommodation-amplitude-diopters",
                                            "50"], "--accommodation-amplitude-diopters must be within 0-20 dioptres")])
def test_a_population_outside_the_ranges_a_campaign_file_keeps_is_refused(capsys, tmp_path, option, says):
    out = tmp_path / "population"
    _refused(capsys, ["population", "jaeken-artal-2012", "-o", str(out), *option], says=says, outputs=[out])


def test_a_psf_of_an_eye_in_ultraviolet_light_is_refused(capsys, tmp_path):
    out = tmp_path / "psf.exr"
    _refused(capsys, ["psf", "--eye-model", "navarro-1985", "--pupil-mm", "3", "--wavelength-nm", "300", "-o",
                      str(out)], says="got 300 nm", outputs=[out])


@pytest.mark.parametrize("step, says", [("0.001", "finer than the image's pixels"), ("0.02", "needs 1681 PSF nodes")])
def test_a_field_step_that_would_run_for_hours_is_refused(capsys, tmp_path, grey_image, step, says):
    out = tmp_path / "out.exr"
    _refused(capsys, ["blur", str(grey_image), "-o", str(out), "--eye-model", "navarro-1985", "--pupil-mm", "3",
                      "--field-step-deg", step], says=says, outputs=[out])


def test_a_zernike_pupil_without_zernikes_is_refused(capsys, tmp_path, grey_image):
    for argv in (["psf", "--rx", "-1", "--pupil-mm", "3", "--zernike-pupil-mm", "4", "-o", str(tmp_path / "p.exr")],
                 ["blur", str(grey_image), "-o", str(tmp_path / "b.exr"), "--rx", "-1", "--pupil-mm", "3",
                  "--zernike-pupil-mm", "4"]):
        _refused(capsys, argv, says="--zernike-pupil-mm 4 mm", outputs=[tmp_path / "p.exr", tmp_path / "b.exr"])


def test_a_threshold_above_the_displays_white_is_reported_never_seen(capsys, tmp_path):
    """An observer who sees nothing the display can show (a legitimate simulation: the procedure flags it) is
    reported as never seen, not as a threshold of 0.9996 (the top of the display's range)."""
    out = tmp_path / "run.json"
    assert main(["atv", "run", "--threshold", "2", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert printed.startswith("never seen: none of the ") and "threshold 0.9" not in printed


def test_a_render_in_light_the_eyes_media_do_not_describe_is_refused(capsys, tmp_path):
    out = tmp_path / "eye.exr"
    _refused(capsys, ["render", "eye", "--wavelength-nm", "355", "--size", "16x16", "--spp", "1", "-o", str(out)],
             says="within 365-850 nm, got 355 nm", outputs=[out])


def test_an_iris_wider_than_a_human_pupil_is_refused_before_a_render(capsys, tmp_path):
    out = tmp_path / "eye.exr"
    _refused(capsys, ["render", "eye", "--iris-mm", "9.5", "--size", "16x16", "--spp", "1", "-o", str(out)],
             says="iris 9.5 mm gives a 10.2 mm entrance pupil", outputs=[out])


def test_a_letter_is_one_sloan_letter(capsys, tmp_path):
    out = tmp_path / "eye.exr"
    _refused(capsys, ["render", "eye", "--letter", "KZ", "--size", "16x16", "--spp", "1", "-o", str(out)],
             says="one Sloan letter", outputs=[out])


@pytest.mark.parametrize("body, says", [
    ('[[item]]\nname = "myope"\nprescription = -40.0', "item[0]: the principal meridian of the prescription -40.00 DS"),
    ('[[sweep]]\nname = "pupil"\npupil_diameter_mm = []', "sweep[0].pupil_diameter_mm: an empty list sweeps nothing"),
    ('[[item]]\nname = "uv"\nwavelength_nm = 355.0', "item[0].wavelength_nm: must be within 365 to 850 nm, got 355.0"),
])
def test_an_eye_campaign_is_refused_at_load(capsys, tmp_path, body, says):
    path, run_dir = tmp_path / "eye.toml", tmp_path / "run"
    path.write_text(EYE_CAMPAIGN.format(body=body))
    _refused(capsys, ["validate", str(path), "-o", str(run_dir)], says=says, outputs=[run_dir])


def test_a_folder_given_as_an_image_is_named_a_folder(capsys, tmp_path):
    folder = tmp_path / "pictures"
    folder.mkdir()
    _refused(capsys, ["blur", str(folder), "-o", str(tmp_path / "out.exr"), "--rx", "-1", "--pupil-mm", "3"],
             says="is a folder, not an image file", outputs=[tmp_path / "out.exr"])


@pytest.mark.parametrize("terms, says", [("2,0=1e6", "Zernike 2,0 = 1e+06 µm, is 1.82e+06 waves at 550 nm"),
                                         ("100,0=0.1", "Zernike 100,0 = 0.1 µm")])
def test_an_absurd_zernike_is_named_when_its_psf_cannot_be_sampled(capsys, tmp_path, terms, says):
    out = tmp_path / "psf.exr"
    _refused(capsys, ["psf", "--zernike", terms, "--pupil-mm", "3", "-o", str(out)], says=says, outputs=[out])


def test_a_campaign_without_a_kind_says_it_was_read_as_a_dslr_campaign(capsys, tmp_path):
    path, run_dir = tmp_path / "eye.toml", tmp_path / "run"
    path.write_text('[campaign]\nname = "x"\npupil_diameter_mm = 3\n[[item]]\nname = "a"\n')
    _refused(capsys, ["validate", str(path), "-o", str(run_dir)],
             says="no [campaign] kind is given, so the file was read as a dslr campaign", outputs=[run_dir])


@pytest.mark.parametrize("extra, said", [
    (["--field-deg", "5,0"], "--field-deg needs --eye-model"),
    (["--field-deg", "5,0", "--accommodation-diopters", "1"], "--field-deg and --accommodation-diopters need --eye-model"),
])
def test_an_option_of_the_traced_eye_alone_is_refused_in_plain_words(capsys, tmp_path, extra, said):
    image = tmp_path / "grey.exr"
    write_image(image, np.full((16, 16), 0.5, np.float32), arcmin_per_px=1.0)
    code = main(["blur", str(image), "--rx", "-1", "--pupil-mm", "3", "-o", str(tmp_path / "out.exr"), *extra])
    err = capsys.readouterr().err
    assert code == 2 and said in err and "(s)" not in err and err.count("\n") == 1


@pytest.mark.parametrize("body, said", [
    ('lens = [{sphere_diopters = "x"}]', "expected a number in dioptres, got 'x'"),
    ("lens = [{sphere_diopters = [1]}]", "expected a number in dioptres, got [1]"),
    ('field_deg = [["a", "b"]]', "expected a number in deg, got 'a'"),
])
def test_a_sweep_value_of_a_wrong_type_is_refused_naming_its_sweep(capsys, tmp_path, body, said):
    # The sweep's configuration names are made before its values are checked: a wrong type must still be refused.
    path = tmp_path / "eye.toml"
    path.write_text(f"[campaign]\nkind = 'eye'\n[[sweep]]\nname = 's'\n{body}\n")
    code = main(["validate", str(path), "-o", str(tmp_path / "run")])
    err = capsys.readouterr().err
    assert code == 2 and "sweep[0] s" in err and said in err and err.count("\n") == 1
    assert not (tmp_path / "run").exists()


def test_an_eye_scene_with_a_pupil_and_an_iris_is_refused_in_its_own_keys(capsys, tmp_path):
    scene = tmp_path / "eye.toml"
    scene.write_text("[eye]\npupil_diameter_mm = 4.0\niris_mm = 3.5\n")
    code = main(["render", "eye", "--scene", str(scene), "-o", str(tmp_path / "e.exr")])
    err = capsys.readouterr().err
    assert code == 2 and "pupil_diameter_mm or iris_mm" in err and "(pupil_mm)" not in err and err.count("\n") == 1
    assert not (tmp_path / "e.exr").exists()
