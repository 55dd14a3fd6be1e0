"""Populations as a campaign kind (``kind = "population"``): the engine runs the library's population.

Oracle: `evaluate_population` called directly on the same eyes and conditions (the library's numbers; the
kind adds the file, the engine's run folder and the report).  Its own numbers are pinned in
tests/test_measured_population.py against each eye evaluated alone.
"""

from __future__ import annotations

import csv

import pytest

from vissim.errors import VissimInputError
from vissim.optics.eyes.measured.population import PopulationCondition, evaluate_population, select_eyes
from vissim.validation.engine.loader import load_campaign
from vissim.validation.engine.validate import validate

SMALL = """
[campaign]
kind = "population"
name = "small population"
dataset = "jaeken-artal-2012"
subjects = [1, 2]
pupil_diameter_mm = [3.0]
field_deg = [[0.0, 0.0], [-15.0, 0.0], [10.0, 0.0]]
correction = ["sphero-cylinder"]
mtf_cyc_per_deg = [10.0, 30.0]
"""


def test_a_population_campaign_gives_the_librarys_numbers_and_its_report(tmp_path):
    path = tmp_path / "population.toml"
    path.write_text(SMALL)
    done = validate(path, tmp_path / "run", show_progress=False)
    assert done.summary.items_total == 3 and done.summary.renders_made == 0
    rows = list(csv.DictReader((tmp_path / "run" / "metrics.csv").open()))
    eyes = select_eyes("jaeken-artal-2012", subjects=[1, 2])
    condition = PopulationCondition(3.0, (-15.0, 0.0), "sphero-cylinder")
    oracle = {r.eye.name: r for r in evaluate_population(eyes, [condition], [10.0, 30.0])}
    mine = {r["eye"]: r for r in rows if r["configuration"] == condition.label}
    assert set(mine) == set(oracle) and len(oracle) == 4
    for name, r in oracle.items():
        assert float(mine[name]["strehl"]) == r.strehl
        assert float(mine[name]["mtf_30_cyc_per_deg"]) == r.mtf[1]
    tables = (tmp_path / "run" / "tables.md").read_text()
    assert "Watson 2013" in tables and "2 eyes of jaeken-artal-2012" not in tables and "4 eyes" in tables
    assert (tmp_path / "run" / "figure_astigmatism.png").exists() and (tmp_path / "run" / "figure_mtf.png").exists()
    again = validate(path, tmp_path / "run", show_progress=False)
    assert again.summary.items_reused == 3


def test_each_condition_is_an_item_spectacles_worn_included(tmp_path):
    path = tmp_path / "population.toml"
    path.write_text(SMALL.replace('correction = ["sphero-cylinder"]', 'correction = ["uncorrected", "-1.00 -0.50 x 90"]'))
    campaign = load_campaign(path)
    assert [c.name for c in campaign.configurations][:2] == [
        "3 mm, field 0,0 deg, 555 nm, uncorrected", "3 mm, field 0,0 deg, 555 nm, wearing -1.00 -0.50 x 90 at 12 mm"]
    assert len(campaign.configurations) == 6
    worn = tmp_path / "worn.toml"  # one worn condition run to its report: the prescription is written as text
    worn.write_text(SMALL.replace('correction = ["sphero-cylinder"]', 'correction = ["-1.00 -0.50 x 90"]')
                    .replace("field_deg = [[0.0, 0.0], [-15.0, 0.0], [10.0, 0.0]]", "field_deg = [[0.0, 0.0]]"))
    validate(worn, tmp_path / "run", show_progress=False)
    with open(tmp_path / "run" / "metrics.csv", newline="") as handle:
        assert {row["correction"] for row in csv.DictReader(handle)} == {"-1.00 -0.50 x 90"}


@pytest.mark.parametrize("line, words", [
    ('pupil_diameter_mm = [5.0]', "campaign.pupil_diameter_mm[0]: must be"),
    ('dataset = "nobody-2020"', "campaign.dataset: choose from"),
    ('correction = ["squinting"]', "campaign.correction[0]: a correction is uncorrected or"),
    ('field_deg = [[0.0]]', "campaign.field_deg[0]"),
    ('spp = 64', "unknown key ['spp']"),
    ('pupil_diameter_mm = [3.0, 3.0]', "given twice"),
    ('subjects = [1, 1]', "campaign.subjects: a population names each subject once"),
    ('subjects = [1, 999]', "campaign.subjects: jaeken-artal-2012 has subjects 1-130, got 999"),
    ('eyes = ["rigth"]', "campaign.eyes: choose from right, left"),
    ('field_deg = [[60.0, 0.0]]', "campaign.field_deg[0]: jaeken-artal-2012 was measured at field x -40 to 40 deg"),
    ('accommodation_amplitude_diopters = 2.0', "goes with the accommodating correction only"),
    ('vertex_distance_mm = 500.0', "campaign.vertex_distance_mm"),
    ('vertex_mm = 12.0', "campaign: 'vertex_mm' is now 'vertex_distance_mm'"),
])
def test_a_bad_population_file_is_refused_naming_its_field(tmp_path, line, words):
    """Each refusal names the file's field; a repeated condition or subject would count an eye twice."""
    key = line.split(" =")[0]
    text = "\n".join(x for x in SMALL.splitlines() if not x.startswith(f"{key} =")) + f"\n{line}\n"
    path = tmp_path / "population.toml"
    path.write_text(text)
    with pytest.raises(VissimInputError, match=words.replace("[", r"\[").replace("(", r"\(").replace(")", r"\)")):
        load_campaign(path)


def test_a_population_campaign_spreads_its_eyes_over_a_dask_scheduler(tmp_path):
    distributed = pytest.importorskip("distributed")
    path = tmp_path / "population.toml"
    path.write_text(SMALL.replace("field_deg = [[0.0, 0.0], [-15.0, 0.0], [10.0, 0.0]]", "field_deg = [0.0, 0.0]"))
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster:
        validate(path, tmp_path / "remote", scheduler=cluster.scheduler_address, show_progress=False)
    validate(path, tmp_path / "here", show_progress=False)
    remote, here = ((tmp_path / d / "metrics.csv").read_text() for d in ("remote", "here"))
    assert remote == here and remote.count("jaeken-artal-2012:") == 4


def test_spp_is_refused_for_a_campaign_without_renders(tmp_path):
    path = tmp_path / "population.toml"
    path.write_text(SMALL)
    with pytest.raises(VissimInputError, match="--spp 64: a population campaign makes no renders"):
        validate(path, tmp_path / "run", spp=64, show_progress=False)
    assert not (tmp_path / "run").exists()
