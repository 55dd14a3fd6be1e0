"""Eye scene files (``vissim render eye --scene``): every key reaches `EyeRender`, bad files fail in one line.

Oracle: the values written into the TOML text here, compared field by field with what the loader
builds (no code shared with `vissim.render.eye_scene_files`).  The command-line tests replace
`render_eye` by a stub that keeps the settings it is given: nothing is rendered, except one
16 x 16, 4 spp render that checks the provenance of a real output.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import vissim.render.eye_render as eye_render_module
from vissim.cli import main
from vissim.errors import VissimInputError
from vissim.imageio import read_image
from vissim.optics.rx.prescription import Prescription
from vissim.render.backend import find_libllvm
from vissim.render.eye_render import EyeRender
from vissim.optics.rx.prescription import Prescription
from vissim.render.eye_scene_files import load_eye_scene

REPO = Path(__file__).resolve().parents[2]

EVERY_KEY = """
[eye]
model = "arizona"
accommodation_diopters = 1.5
pupil_diameter_mm = 4.5
prescription = "-2.00 -0.50 x 90"
field_deg = [5.0, -2.5]
[light]
wavelength_nm = 600.0
spectrum = "mono"
[chart]
chart_distance_m = 0.5
letter = "H"
logmar = 0.3
[spectacles]
vertex_distance_mm = 14.0
sphere_diopters = -1.25
cylinder_diopters = -0.75
axis_deg = 30.0
[render]
size_px = [16, 24]
arcmin_per_px = 0.5
spp = 4
seed = 7
"""
EVERY_FIELD = dict(model="arizona", accommodation_diopters=1.5, pupil_mm=4.5, iris_mm=None, field_deg=(5.0, -2.5),
                   wavelength_nm=600.0, spectrum="mono", chart_distance_m=0.5, letter="H", logmar=0.3,
                   vertex_mm=14.0, lens=(-1.25, -0.75, 30.0), size_px=(16, 24), arcmin_per_px=0.5, spp=4, seed=7,
                   rx=Prescription.parse("-2.00 -0.50 x 90"))


def scene(tmp_path: Path, text: str, name: str = "eye.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_every_key_reaches_the_render_settings(tmp_path):
    settings = load_eye_scene(scene(tmp_path, EVERY_KEY))
    for field, expected in EVERY_FIELD.items():
        assert getattr(settings, field) == expected, field


def test_the_iris_and_the_photopic_spectrum(tmp_path):
    settings = load_eye_scene(scene(tmp_path, '[eye]\niris_mm = 5.0\n[light]\nspectrum = "photopic"\n'))
    assert (settings.pupil_mm, settings.iris_mm, settings.spectrum, settings.wavelength_nm) == (None, 5.0, "photopic",
                                                                                                 None)


def test_an_empty_file_is_the_default_render(tmp_path):
    assert load_eye_scene(scene(tmp_path, "# nothing\n")) == EyeRender()


def test_the_shipped_scene_loads_and_writes_down_the_defaults():
    """scenes/eye.toml says that the values written in it are the defaults: they are."""
    assert load_eye_scene(REPO / "scenes" / "eye.toml") == EyeRender()


BAD = [  # (file text, fragments the one error line must hold besides the file's path)
    ("[camera]\nf_number = 5\n", ["unknown key 'camera'"]),
    ("[eye]\npupil_mm = 3\n", ["[eye]", "'pupil_mm' is now 'pupil_diameter_mm'"]),
    ("[spectacles]\nvertex_mm = 12\n", ["[spectacles]", "'vertex_mm' is now 'vertex_distance_mm'"]),
    ("[eye]\nrx = \"-1.00\"\n", ["[eye]", "'rx' is now 'prescription'"]),
    ("[chart]\ndistance_mm = 6000\n", ["[chart]", "'distance_mm' is now 'chart_distance_m' (metres, not mm)"]),
    ("[chart]\ndistance_m = 6.0\n", ["[chart]", "'distance_m' is now 'chart_distance_m'"]),
    ("[eye]\npupil_diameter_mm = \"3\"\n", ["[eye].pupil_diameter_mm", "mm"]),
    ("[render]\nspp = 4.5\n", ["[render].spp", "samples per pixel"]),
    ("[render]\nsize_px = [16]\n", ["[render].size_px", "pixels"]),
    ("[eye]\nfield_deg = [1.0, \"up\"]\n", ["[eye].field_deg", "degrees"]),
    ("[eye]\npupil_diameter_mm = 30.0\n", ["[eye].pupil_diameter_mm", "mm", "30"]),
    ("[light]\nwavelength_nm = 1000.0\n", ["[light].wavelength_nm", "nm", "1000"]),
    ("[render]\narcmin_per_px = 0.0\n", ["[render].arcmin_per_px", "arcmin per pixel"]),
    ("[chart]\nchart_distance_m = -1.0\n", ["[chart].chart_distance_m", " m"]),
    ("[spectacles]\nvertex_distance_mm = 201.0\n", ["[spectacles].vertex_distance_mm", "within 0-200 mm"]),  # 0: a lens at the cornea
    ("[spectacles]\nsphere_diopters = 40.0\n", ["[spectacles].sphere_diopters", "dioptres", "40"]),
    ("[spectacles]\ncylinder_diopters = -1.0\n", ["[spectacles].cylinder_diopters", "axis_deg", "degrees"]),
    ("[render]\nspp = 0\n", ["[render].spp", "samples per pixel"]),
    ("[eye]\nmodel = \"gullstrand\"\n", ["[eye].model", "gullstrand"]),
    ("[eye]\nmodel = \"le-grand\"\naccommodation_diopters = 2.0\n", ["accommodation_diopters", "got 2 D"]),
    ("[chart]\nletter = \"Q\"\n", ["[chart].letter", "Q"]),
    ("[spectacles]\ncylinder_diopters = -1.0\naxis_deg = 200.0\n", ["[spectacles]", "axis_deg", "deg", "200"]),
    ("[eye]\npupil_diameter_mm = 3.0\niris_mm = 4.0\n", ["pupil", "iris_mm", "not both"]),
    ("[eye]\nfield_deg = [50.0, 0.0]\n", ["[eye].field_deg", "50", "deg"]),
    ("[light]\nwavelength_nm = 550.0\nspectrum = \"photopic\"\n", ["wavelength", "photopic"]),
    ("[eye]\nprescription = \"minus two\"\n", ["[eye].prescription", "minus two", "dioptres"]),
    ("[eye\n", ["not valid TOML"]),
]


@pytest.mark.parametrize("text, fragments", BAD, ids=[text.split("\n")[0] + str(i) for i, (text, _) in enumerate(BAD)])
def test_a_bad_file_is_refused_in_one_line_naming_it(tmp_path, text, fragments):
    path = scene(tmp_path, text)
    with pytest.raises(VissimInputError) as raised:
        load_eye_scene(path)
    message = str(raised.value)
    assert "\n" not in message and str(path) in message, message
    for fragment in fragments:
        assert fragment in message, message


class _Kept(Exception):
    """Raised by the stub renderer, carrying the settings the command built."""


@pytest.fixture
def kept_settings(monkeypatch):
    def stub(settings, variant=None):
        raise _Kept(settings)

    monkeypatch.setattr(eye_render_module, "render_eye", stub)

    def run(*argv) -> EyeRender:
        with pytest.raises(_Kept) as kept:
            main(["render", "eye", *map(str, argv)])
        return kept.value.args[0]

    return run


def test_no_options_no_file_is_the_default_render(tmp_path, kept_settings):
    """One set of defaults: the command's equal `EyeRender`'s."""
    assert kept_settings("-o", tmp_path / "o.exr") == EyeRender()


def test_options_override_the_file(tmp_path, kept_settings):
    path = scene(tmp_path, EVERY_KEY)
    settings = kept_settings("--scene", path, "--iris-mm", "6", "--spectrum", "photopic", "--logmar", "0.7",
                             "--sphere", "1.5", "--size", "8x8", "--eye-model", "navarro-1985", "-o",
                             tmp_path / "o.exr")
    assert (settings.pupil_mm, settings.iris_mm) == (None, 6.0)
    assert (settings.spectrum, settings.wavelength_nm) == ("photopic", None)
    assert (settings.logmar, settings.size_px, settings.model) == (0.7, (8, 8), "navarro-1985")
    assert settings.lens == (1.5, 0.0, 180.0)  # the option's lens replaces the file's
    # what no option overrides stays the file's
    assert (settings.chart_distance_m, settings.letter, settings.vertex_mm, settings.seed) == (0.5, "H", 14.0, 7)
    assert settings.field_deg == (5.0, -2.5) and settings.accommodation_diopters == 1.5


def test_a_wavelength_option_overrides_the_files_spectrum(tmp_path, kept_settings):
    path = scene(tmp_path, '[light]\nspectrum = "photopic"\n[eye]\niris_mm = 5.0\n')
    settings = kept_settings("--scene", path, "--wavelength-nm", "500", "--pupil-mm", "2", "-o", tmp_path / "o.exr")
    assert (settings.spectrum, settings.wavelength_nm, settings.pupil_mm, settings.iris_mm) == ("mono", 500.0, 2.0,
                                                                                                None)


def test_the_output_is_never_the_scene_file(tmp_path, capsys):
    path = scene(tmp_path, "[chart]\nletter = \"H\"\n", "eye.exr")
    before = path.read_bytes()
    assert main(["render", "eye", "--scene", str(path), "-o", str(path), "--overwrite"]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and err.startswith("vissim: error: "), err
    assert path.read_bytes() == before


def test_a_bad_scene_file_fails_the_command_in_one_line(tmp_path, capsys):
    path = scene(tmp_path, "[eye]\npupil_diameter_mm = 30.0\n")
    assert main(["render", "eye", "--scene", str(path), "-o", str(tmp_path / "o.exr")]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and str(path) in err and "[eye].pupil_diameter_mm" in err, err


@pytest.mark.skipif(find_libllvm() is None, reason="no usable libLLVM: llvm variants unavailable")
def test_the_scene_file_is_in_the_provenance(tmp_path):
    path = scene(tmp_path, '[chart]\nletter = "H"\nlogmar = 0.3\n[render]\nsize_px = [16, 16]\nspp = 4\n')
    output = tmp_path / "o.exr"
    assert main(["render", "eye", "--scene", str(path), "--seed", "3", "-o", str(output)]) == 0
    inputs = read_image(output).provenance["inputs"]
    assert inputs["scene_file"] == str(path)
    assert (inputs["eye"]["letter"], inputs["eye"]["size_px"], inputs["eye"]["seed"]) == ("H", [16, 16], 3)


@pytest.mark.skipif(find_libllvm() is None, reason="no usable libLLVM: llvm variants unavailable")
def test_a_scene_file_renders_the_image_its_options_render(tmp_path):
    """The same settings written in a file or given as options: the same pixels, bit for bit (fixed seed)."""
    path = scene(tmp_path, '[eye]\npupil_diameter_mm = 4.0\naccommodation_diopters = 1.0\n[chart]\nchart_distance_m = 2.0\n'
                           'letter = "Z"\nlogmar = 0.4\n[spectacles]\nsphere_diopters = 0.5\n'
                           '[render]\nsize_px = [16, 16]\nspp = 4\nseed = 9\n')
    from_file, from_options = tmp_path / "file.exr", tmp_path / "options.exr"
    assert main(["render", "eye", "--scene", str(path), "-o", str(from_file)]) == 0
    assert main(["render", "eye", "--pupil-mm", "4", "--accommodation-diopters", "1", "--chart-distance-m", "2",
                 "--letter", "Z", "--logmar", "0.4", "--sphere", "0.5", "--size", "16x16", "--spp", "4",
                 "--seed", "9", "-o", str(from_options)]) == 0
    a, b = read_image(from_file), read_image(from_options)
    assert a.pixels.shape == (16, 16) and a.pixels.std() > 0  # a letter, not a blank field: the test can fail
    assert np.array_equal(a.pixels, b.pixels)
    assert a.provenance["inputs"]["eye"] == b.provenance["inputs"]["eye"]
