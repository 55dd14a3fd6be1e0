"""Metrics are registered once (vissim.validation.engine.metrics), with one PSNR.

* The one PSNR (`vissim.imaging.metrics.psnr_db`) is scikit-image's, to the last bit (oracle:
  `skimage.metrics.peak_signal_noise_ratio`, which shares no code with it).
* No module of the validation package spells a metric's key: each reads it from the registry.
* A new metric is one registration: every kind's items score it and every kind's rows show it.
"""

import ast
import math
from pathlib import Path

import numpy as np
import pytest
from skimage.metrics import peak_signal_noise_ratio

from vissim.errors import VissimInputError
from vissim.imaging.metrics import compare_images, psnr_db
from vissim.validation.depth.report import depth_rows
from vissim.validation.dslr.report import metrics_rows
from vissim.validation.dslr.wave_bench import TRACED_RAYS
from vissim.validation.dslr.wave_bench_report import self_check_table
from vissim.validation.engine import metrics
from vissim.validation.engine.metrics import (METRICS, MEAN_ABS_DIFF, PSNR, SSIM, Metric, added_scores, floor_column,
                                              register_metric)
from vissim.validation.engine.summary import NO_LENS
from vissim.validation.eye.report import eye_report

VALIDATION = Path(metrics.__file__).resolve().parents[1]


def test_the_one_psnr_is_scikit_image_s_to_the_last_bit():
    rng = np.random.default_rng(7)
    for _ in range(200):
        reference = rng.uniform(0.0, 1.0, (16, 16))
        test = reference + rng.normal(0.0, 10.0 ** rng.uniform(-6, -1), reference.shape)
        mse = float(np.mean((reference - test) ** 2))
        expected = float(peak_signal_noise_ratio(reference, test, data_range=1.0))
        assert psnr_db(mse, 1.0) == expected
        assert compare_images(reference, test, data_range=1.0).psnr_db == expected
    assert psnr_db(0.0, 1.0) == math.inf


def test_no_validation_module_spells_a_metric_s_key():
    keys = {m.name for m in METRICS.values()} | {floor_column(m) for m in METRICS.values()}
    found = []
    for path in sorted(VALIDATION.rglob("*.py")):
        if path == Path(metrics.__file__).resolve():
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and node.value in keys:
                found.append(f"{path.relative_to(VALIDATION)}:{node.lineno}: {node.value!r}")
    assert not found, "metric keys spelled outside the registry:\n" + "\n".join(found)


def test_a_metric_name_is_registered_once():
    with pytest.raises(VissimInputError, match="'psnr_db' is registered already"):
        register_metric(Metric(PSNR.name, "PSNR", "dB", True, 2, lambda comparison, mask: 0.0))


@pytest.fixture
def peak_metric(monkeypatch):
    """A new metric, registered as a plug-in would: the largest absolute difference."""
    monkeypatch.setattr(metrics, "METRICS", dict(METRICS))
    def largest(comparison, mask):
        return float(comparison.abs_diff_map.max() if mask is None else comparison.abs_diff_map[mask].max())
    return register_metric(Metric("peak_abs_diff", "peak AD", "", False, 4, largest))


def _comparison_record(comparison) -> dict:
    return {**comparison.as_json(), **added_scores(comparison)}


def test_a_new_metric_is_one_registration_and_reaches_every_kind_s_rows(peak_metric):
    reference = np.zeros((16, 16))
    test = reference.copy()
    test[3, 4] = 0.25
    comparison = compare_images(reference, test, data_range=1.0)
    scored = _comparison_record(comparison)
    assert scored[peak_metric.name] == 0.25
    dslr = {"key": "k", "lens_label": "no lens", "configuration": {"name": "c", "letter": "K", "logmar": 1.0,
                                                                    "polarity": "black-on-white"},
            "noise_floor": {"geometric": scored},
            "comparisons": [{"simulation": "geometric", "input": "render", "reference_kind": "geometric",
                             "metrics": scored, "registration": {"shift_rows_px": 0.0, "shift_cols_px": 0.0},
                             "setup": {"camera_prescription": "plano DS", "pupil_diameter_mm": 3.6}}]}
    depth = {"key": "k", "configuration": {"name": "c", "viewer_label": "eye"},
             "comparisons": [{"simulation": "geometric layered", "regions": {"all": {**scored, "n_px": 256}},
                              "noise_floor": {"all": {**scored, "n_px": 256}}, "depth_blur": {"n_layers": 1}}]}
    eye = {"configuration": {"name": "c", "spectrum": "mono", "wavelength_nm": 550.0, "lens": None,
                             "field_deg": [0.0, 0.0], "pupil_mm": 3.0, "accommodation_diopters": 0.0,
                             "letter": "K", "logmar": 0.5},
           "noise_floor": scored, "rows": [{"simulation": "traced_rays", "reference": "render",
                                            PSNR.name: 40.0, SSIM.name: 0.99, "over_floor_db": 3.0,
                                            peak_metric.name: 0.25}], "costs_db": {}}
    assert metrics_rows([dslr])[0][peak_metric.name] == 0.25
    assert depth_rows([depth])[0][peak_metric.name] == 0.25
    assert eye_report([eye]).rows[0][peak_metric.name] == 0.25


def test_the_self_check_note_on_lens_free_rows_reads_their_metrics_from_the_registry():
    """A no-lens traced-rays row below the self-check's margin gets the note on the rasterisation, with its mean AD."""
    row = {"configuration": "bare", "group": "g", "lenses": NO_LENS, "simulation": TRACED_RAYS, "input": "synthetic",
           "reference": "render (no diffraction)", PSNR.name: 40.0, floor_column(PSNR): 39.0,
           MEAN_ABS_DIFF.name: 2.5e-3}
    table = self_check_table([row])
    assert "Without lenses (1): +1.0 dB over the floor (40.0 dB against 39.0 dB)" in table
    assert "They differ by 2.5e-03 on average" in table
