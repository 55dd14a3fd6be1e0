"""The DSLR bench scene dict and its TOML scene files, without rendering.

Expected values: the thesis's bench (Krueger 2015, section 4.4: 18 mm at f/5, trial lenses
10 mm in front, chart at 914.4 mm); entrance pupil f/N (ERRATA item 3).
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from vissim.bench.dslr.bench import DslrBench, chart_mm_per_texel, dslr_scene
from vissim.bench.lenses.mesh import rim_thickness_mm
from vissim.bench.dslr.scene_files import load_bench_toml, load_chart_toml
from vissim.errors import VissimInputError
from vissim.optics.rx.trial_lens import TrialLens

SCENE = Path(__file__).resolve().parents[2] / "scenes" / "dslr_bench.toml"


@pytest.fixture(autouse=True)
def _mesh_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("VISSIM_CACHE_DIR", str(tmp_path / "cache"))


def scene_of(bench: DslrBench) -> dict:
    return dslr_scene(bench, np.full((64, 64), 0.9, np.float32), chart_mm_per_texel(bench))


def test_camera_is_the_thesis_dslr_with_an_explicit_near_clip():
    camera = scene_of(DslrBench())["camera"]
    assert camera["type"] == "thinlens" and camera["aperture_radius"] == pytest.approx(1.8)  # 18 mm / 5 / 2
    assert camera["focus_distance"] == 914.4
    assert camera["near_clip"] < 10.0  # below the vertex distance: the lens is not clipped away
    assert camera["fov_axis"] == "x"
    assert math.tan(math.radians(camera["fov"] / 2)) == pytest.approx(56.5 * math.tan(math.radians(1 / 60)))
    film = camera["film"]
    assert (film["height"], film["width"]) == (133, 113) and film["rfilter"] == {"type": "box"}


def test_lenses_stack_from_the_vertex_distance_towards_the_chart():
    bench = DslrBench(lenses=(TrialLens(-2.0), TrialLens(3.0), TrialLens(0.0, 1.0, 45.0)), lens_gap_mm=2.0)
    z = bench.lens_back_vertex_z_mm()
    lenses = bench.physical_lenses
    assert z[-1] == 10.0
    assert z[1] == pytest.approx(z[2] + lenses[2].center_thickness_mm + 2.0)
    assert z[0] == pytest.approx(z[1] + lenses[1].center_thickness_mm + 2.0)
    scene = scene_of(bench)
    for i, depth in enumerate(z):
        shape = scene[f"lens_{i}"]
        assert Path(shape["filename"]).is_file() and shape["to_world"][2][3] == depth
        assert shape["bsdf"] == {"type": "vissim_refract", "int_ior": 1.523, "fresnel_loss": False}


def test_thin_lenses_become_realistic_crown_lenses_used_by_the_theory_too():
    bench = DslrBench(lenses=(TrialLens(4.0), TrialLens(-4.0)))
    plus, minus = bench.physical_lenses
    aperture = bench.clear_aperture()
    assert rim_thickness_mm(plus, aperture)[0] == pytest.approx(1.0) and minus.center_thickness_mm == 1.0
    assert bench.trial_lens_setup().lenses == (plus, minus)
    farthest_mm = bench.lens_back_vertex_z_mm()[0] + plus.center_thickness_mm
    beam = bench.entrance_pupil_diameter_mm + 2 * farthest_mm * math.tan(bench.field_half_diagonal_rad)
    assert aperture > beam


def test_chart_covers_the_field_and_is_finer_than_the_camera_pixel():
    bench = DslrBench(lenses=(TrialLens(4.0),))
    chart = scene_of(bench)["chart"]
    half_width_mm, half_height_mm = -chart["to_world"][0][0], chart["to_world"][1][1]
    assert chart["to_world"][2][3] == 914.4 and chart["to_world"][2][2] == -1.0  # faces the camera
    field_half = [0.5 * n * bench.pitch_mm * 1.05 for n in (113, 133)]
    assert half_width_mm > field_half[0] and half_height_mm > field_half[1]
    assert chart_mm_per_texel(bench) <= bench.pitch_mm / 4
    texture = chart["emitter"]["radiance"]
    assert texture["filter_type"] == "nearest" and texture["data"].dtype == np.float32


def test_scene_builders_do_not_import_mitsuba():
    code = "import sys, vissim.bench.dslr.bench, vissim.bench.dslr.scene_files; print('mitsuba' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "False"


@pytest.mark.parametrize("kwargs, message", [
    ({"sampler": "sobol"}, "sampler"),
    ({"lenses": (TrialLens(1.0),) * 4}, "at most|up to"),
    ({"size_px": (10,)}, "size_px"),
    ({"spp": 0}, "spp"),
    ({"f_number": -5}, "f number"),
])
def test_bad_bench_parameters_name_the_value(kwargs, message):
    with pytest.raises(VissimInputError, match=message):
        DslrBench(**kwargs)


def test_example_scene_file_loads_as_the_thesis_bench():
    bench, chart = load_bench_toml(SCENE)
    assert bench.entrance_pupil_diameter_mm == pytest.approx(3.6) and bench.vertex_distance_mm == 10.0
    assert [lens.sphere_diopters for lens in bench.lenses] == [2.0]
    assert chart.rows[0].letters == "R" and chart.rows[0].logmar == 1.0
    assert chart.viewing_distance_m == pytest.approx(0.9144)
    assert load_bench_toml(SCENE, spp=16, lenses=())[0].lenses == ()


@pytest.mark.parametrize("text, message", [
    ("[camera]\nfocal_lenght_mm = 18\n", "unknown key 'focal_lenght_mm'"),
    ("[camera]\nf_number = 'five'\n", "f_number must be a number"),
    ("[[holder.lenses]]\naxis_deg = 90\n", "needs sphere_diopters"),
    ("[chart]\nletter = 'R'\nletters = 'NCKZO'\n", "either letter"),
    ("[image]\nsize_px = [133]\n", "size_px"),
    ("[lamp]\n", "unknown key 'lamp'"),
    ("not toml [", "not valid TOML"),
])
def test_bad_scene_files_are_refused_with_the_key_named(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(VissimInputError, match=message):
        load_bench_toml(path)


def test_chart_file_can_hold_an_etdrs_chart(tmp_path):
    path = tmp_path / "chart.toml"
    path.write_text('[chart]\nletters = "NCKZO HVORS"\nlogmar_range = [1.0, 0.9]\npolarity = "white-on-black"\n')
    spec = load_chart_toml(path, 914.4)
    assert [row.letters for row in spec.rows] == ["NCKZO", "HVORS"] and spec.polarity == "white-on-black"
