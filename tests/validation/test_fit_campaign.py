"""``fit_rx = true``: each capture with lenses is fitted and the report gets the fit table (stand-in bench)."""

import json

from fake_bench import fake_render

from vissim.validation.engine.report import load_results, write_report
from vissim.validation.engine.runner import run_campaign

FIT_CAMPAIGN = """
[campaign]
name = "fit"
spp = 4
seeds = [1, 2]
tile_px = [64, 64]
simulations = ["geometric"]
inputs = ["render"]
wave_truth = false
fit_rx = true

[[item]]
name = "plus two"
letter = "K"
logmar = 0.7
lenses = [2.0]

[[item]]
name = "no lens"
letter = "K"
logmar = 0.7
"""


def test_a_campaign_with_fit_rx_fits_each_capture_and_reports_it_beside_vergence_theory(tmp_path, campaign_file):
    campaign = campaign_file(FIT_CAMPAIGN, "fit.toml")
    assert campaign.settings.fit_rx
    run_dir = tmp_path / "run"
    run_campaign(campaign, run_dir, render=fake_render, show_progress=False)
    results = {r["configuration"]["name"]: r for r in load_results(run_dir)}
    assert results["no lens"]["fit_rx"] is None  # nothing to fit without a lens
    fit = results["plus two"]["fit_rx"]
    comparison = fit["comparison"]
    assert comparison["fit_status"] == "ok", comparison
    # The stand-in bench is vergence theory's blur and magnification (trial_lens_effect) plus
    # noise: the fit must find that power, within its interval.
    assert comparison["agrees"] is True, comparison
    assert max(abs(e) for e in comparison["errors_diopters"].values()) < 0.05
    assert comparison["table_4_2"] and comparison["vergence_theory"]
    json.dumps(fit)  # the record is plain JSON
    write_report(run_dir)
    tables = (run_dir / "tables.md").read_text()
    assert "Prescription fit of each capture" in tables
    fits = tables.split("Prescription fit of each capture")[1]
    row = next(line for line in fits.splitlines() if line.startswith("| plus two | +2.00 DS"))
    assert "agrees" in row


def test_fit_rx_is_off_unless_asked_for(campaign_file):
    assert campaign_file(FIT_CAMPAIGN.replace("fit_rx = true", ""), "nofit.toml").settings.fit_rx is False
    try:
        campaign_file(FIT_CAMPAIGN.replace("fit_rx = true", 'fit_rx = "yes"'), "nofit.toml")
    except Exception as exc:  # noqa: BLE001 - the message is what is checked
        assert "campaign.fit_rx" in str(exc) and "true or false" in str(exc)
    else:
        raise AssertionError("fit_rx = \"yes\" was accepted")
