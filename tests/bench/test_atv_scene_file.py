"""The ATV tube as an editable scene file (scenes/atv_tube.toml)."""

import pytest

from vissim.bench.atv.tube import AtvConfig, AtvTube
from vissim.bench.atv.scene_files import load_atv_toml
from vissim.errors import VissimInputError


def test_shipped_atv_scene_is_the_thesis_tube_with_a_plus_two_lens():
    config = load_atv_toml("scenes/atv_tube.toml")
    assert config.tube == AtvTube()  # the file writes the defaults out: 125 mm, 8 D, 326 ppi
    assert config.trial_lens.sphere_diopters == 2.0 and config.trial_lens_distance_mm == 15.0
    error = config.eye.refractive_error  # AtvEye normalises "no error" to a zero RefractiveError
    assert config.eye.pupil_diameter_mm == 4.0 and error.sphere_diopters == 0 and error.cylinder_diopters == 0


def test_atv_scene_with_an_eye_prescription_and_no_lens(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('[eye]\nprescription = "+1.25 DS"\npupil_diameter_mm = 6.0\n')
    config = load_atv_toml(path)
    assert config.trial_lens is None and config.eye.pupil_diameter_mm == 6.0
    assert config.eye.refractive_error is not None
    assert isinstance(config, AtvConfig)


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("[tube]\nlength = 3\n", "unknown key"),
        ("[eye]\npupil_diameter_mm = 'wide'\n", "must be a number in mm"),
        ("[eye]\npupil_diameter_mm = 12.0\n", "pupil"),
        ("[lamp]\n", "unknown key"),
    ],
)
def test_bad_atv_scene_files_get_one_clear_error(tmp_path, text, fragment):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(VissimInputError, match=fragment):
        load_atv_toml(path)
