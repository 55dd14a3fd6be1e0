"""One set of ranges (`vissim.checks`): the API, the command line and the campaign files refuse alike.

The vertex distance once had three limits (>= 0 in `DslrBench`, <= 200 mm in campaigns,
<= 1000 mm in ``fit-rx``); it now has `VERTEX_DISTANCE_RANGE_MM`, checked by one function.
"""

import pytest

from vissim.atv.virtual import AtvApparatus
from vissim.bench.dslr.bench import DslrBench
from vissim.checks import VERTEX_DISTANCE_RANGE_MM, vertex_distance_mm
from vissim.cli import main
from vissim.errors import VissimInputError
from vissim.optics.trial_lens import TrialLens, TrialLensSetup, thesis_table_4_2_power

API = {
    "DslrBench": lambda mm: DslrBench(vertex_distance_mm=mm),
    "TrialLensSetup": lambda mm: TrialLensSetup((TrialLens(2.0),), vertex_distance_mm=mm),
    "AtvApparatus": lambda mm: AtvApparatus(trial_lens_vertex_mm=mm),
    "thesis_table_4_2_power": lambda mm: thesis_table_4_2_power(2.0, mm),
    "checks": vertex_distance_mm,
}


def test_the_vertex_distance_range_holds_a_trial_frame():
    # the thesis's bench: 10 mm; spectacles: 12-15 mm; 200 mm: the widest any campaign took before
    assert VERTEX_DISTANCE_RANGE_MM == (0.0, 200.0)


@pytest.mark.parametrize("api", sorted(API))
def test_every_api_takes_the_range_and_refuses_beyond_it(api):
    low, high = VERTEX_DISTANCE_RANGE_MM
    for inside in (low, 10.0, high):
        API[api](inside)
    for outside in (low - 1.0, high + 1.0):
        with pytest.raises(VissimInputError, match=r"within 0-200 mm"):
            API[api](outside)


@pytest.mark.parametrize("value, refused", [("200", False), ("201", True), ("-1", True)])
def test_fit_rx_takes_the_same_range(tmp_path, capsys, value, refused):
    missing = str(tmp_path / "missing.exr")  # a refused --vertex-mm is caught before any file is read
    code = main(["fit-rx", missing, "--reference", missing, "--pupil-mm", "3.6", "--vertex-mm", value,
                 "--object-distance-m", "1"])
    err = capsys.readouterr().err
    assert code == 2
    assert ("--vertex-mm" in err) is refused, err
