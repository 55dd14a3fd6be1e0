"""Populations of measured eyes: each eye's numbers are the single eye's, the filter reads the data, the
summary is the quantiles of the eyes.

Oracles: `eye_wavefront` of each eye built alone (the population traces the base eye once per condition),
the raw data file's defocus with the base eye's traced chromatic shift and Thibos et al.'s M = -4√3 c20 / r²
(2004), numpy's quantiles.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from vissim.errors import VissimInputError
from vissim.optics.eyes.eye import build_eye
from vissim.optics.eyes.measured import datasets
from vissim.optics.eyes.measured.measured_eye import parse_measured_eye
from vissim.optics.eyes.measured.population import (PopulationCondition, evaluate_population, population_conditions,
                                                    population_quantiles, select_eyes)
from vissim.optics.eyes.psf_wavefront import eye_wavefront
from vissim.optics.psf.compute import strehl_ratio
from vissim.optics.pupil.wavefront import Wavefront
from vissim.optics.rx.prescription import Prescription

EYES = select_eyes("jaeken-artal-2012", subjects=[3, 17, 40], eyes=["right", "left"])


def test_each_eye_is_the_eye_alone():
    condition = PopulationCondition(3.0, (10.0, 0.0), "sphero-cylinder", 555.0)
    for result in evaluate_population(EYES, [condition]):
        alone = eye_wavefront(build_eye(result.eye.name, pupil_diameter_mm=3.0), wavelength_nm=555.0, field_deg=(10.0, 0.0))
        higher = {k: v for k, v in alone.coefficients_um.items() if k[0] >= 3}
        assert result.strehl == pytest.approx(strehl_ratio(Wavefront(higher, 3.0, 555.0), wavelength_nm=555.0),
                                              rel=1e-9)
        c20 = alone.coefficients_um[(2, 0)]
        assert result.m_diopters == pytest.approx(-4 * math.sqrt(3) * c20 / 1.5 ** 2, rel=1e-9)
        assert result.higher_order_rms_um == pytest.approx(math.sqrt(sum(v * v for v in higher.values())), rel=1e-9)


def test_uncorrected_eyes_see_worse_than_corrected_ones():
    frequencies = [5.0, 10.0, 20.0]
    plain, corrected = (evaluate_population(EYES, [PopulationCondition(4.0, correction=c)], frequencies)
                        for c in ("uncorrected", "sphero-cylinder"))
    for a, b in zip(plain, corrected):
        assert a.eye == b.eye and a.strehl <= b.strehl + 1e-12
        assert np.all(b.mtf <= 1.0) and b.mtf[0] > b.mtf[-1]


def test_the_spherical_equivalent_filter_reads_the_data():
    raw = np.load(datasets.DATA_DIR / "jaeken-artal-2012.npz")
    centre = list(raw["field_deg"]).index(0.0)
    base = build_eye("navarro-1985", pupil_diameter_mm=4.0)
    shift = (eye_wavefront(base, wavelength_nm=555.0).coefficients_um[(2, 0)]
             - eye_wavefront(base, wavelength_nm=780.0).coefficients_um[(2, 0)])
    subjects = list(range(1, 31))
    kept = {e.subject for e in select_eyes("jaeken-artal-2012", subjects=subjects, eyes=["right"],
                                           foveal_se_within_diopters=(-0.5, 0.5))}
    expected = set()
    for s in subjects:
        c20 = raw["zernike_um"][s - 1, 0, centre, 4]
        if not np.isnan(c20) and -0.5 <= -4 * math.sqrt(3) * (c20 + shift) / 2.0 ** 2 <= 0.5:
            expected.add(s)
    assert kept == expected and 0 < len(kept) < len(subjects)


def test_the_summary_is_the_quantiles_across_eyes():
    condition = PopulationCondition(3.0)
    results = evaluate_population(EYES, [condition], [10.0, 30.0])
    table = population_quantiles(results, quantiles=(0.25, 0.5))[condition.label]
    assert table["count"] == len(EYES)
    np.testing.assert_allclose(table["strehl"], np.quantile([r.strehl for r in results], [0.25, 0.5]))
    np.testing.assert_allclose(table["mtf"][1], np.median([r.mtf for r in results], axis=0))


def test_eyes_not_measured_at_a_field_are_skipped_and_named(caplog):
    eyes = select_eyes("jaeken-artal-2012", subjects=[17], eyes=["right", "left"])
    with caplog.at_level(logging.INFO, logger="vissim.optics.eyes.measured.population"):
        results = evaluate_population(eyes, [PopulationCondition(3.0, (-15.0, 0.0))])
    assert [r.eye.name for r in results] == ["jaeken-artal-2012:17:left"]
    assert "jaeken-artal-2012:17:right" in caplog.text


@pytest.mark.parametrize("kwargs, words", [({"correction": "contact lens"}, "one of uncorrected, sphero-cylinder"),
                                           ({"wavelength_nm": 0.0}, "wavelength"),
                                           ({"field_deg": (1.0,)}, "field is \\(x, y\\)"),
                                           ({"field_deg": ("a", 0)}, "field angle")])
def test_bad_conditions_are_refused(kwargs, words):
    with pytest.raises(VissimInputError, match=words):
        PopulationCondition(3.0, **kwargs)


def test_a_pupil_larger_than_the_datas_is_refused_not_skipped():
    with pytest.raises(VissimInputError, match="measured over a 4 mm pupil"):
        evaluate_population(EYES[:1], [PopulationCondition(5.0)])


def _same(a, b):
    """Same eyes and conditions in the same order, and the same numbers up to summation order (processes may
    run BLAS with other thread counts: 1e-12 relative, measured apart by at most 4e-16)."""
    assert [(r.eye, r.condition) for r in a] == [(r.eye, r.condition) for r in b]
    for x, y in zip(a, b):
        np.testing.assert_allclose([x.strehl, x.m_diopters, *x.mtf], [y.strehl, y.m_diopters, *y.mtf], rtol=1e-12,
                                   atol=1e-15)


def test_processes_and_a_dask_scheduler_give_the_same_numbers():
    distributed = pytest.importorskip("distributed")
    conditions = [PopulationCondition(3.0), PopulationCondition(4.0, (10.0, 0.0), "uncorrected")]
    eyes = EYES[:3]
    serial = evaluate_population(eyes, conditions, [10.0, 30.0])
    pooled = evaluate_population(eyes, conditions, [10.0, 30.0], workers=2, chunk_eyes=2)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            remote = evaluate_population(eyes, conditions, [10.0, 30.0], client=client, chunk_eyes=2)
    _same(pooled, serial)
    _same(remote, serial)


def test_a_schematic_eyes_refraction_is_taken_as_the_measured_eyes_are():
    # Over the pupil seen along the chief ray, at the pupil: Escudero-Sanz's oblique astigmatism at 1 mm, 543 nm
    # is the tangential-sagittal difference optiland's real-ray foci give (tests/test_eye_oblique_refraction.py:
    # 0.20/0.84/2.00/3.85 D at the corneal vertex, within 0.05 D of this plane's).
    from vissim.optics.eyes.measured.population import schematic_refraction
    from vissim.optics.eyes.models import eye_model
    for field, at_vertex in ((10.0, 0.20), (20.0, 0.84), (30.0, 2.00), (40.0, 3.85)):
        _, j0, j45 = schematic_refraction(eye_model("escudero-sanz-1999"),
                                          PopulationCondition(1.0, (field, 0.0), "uncorrected", 543.0))
        assert 2 * math.hypot(j0, j45) == pytest.approx(at_vertex, abs=0.05)


def test_an_eye_with_the_higher_strehl_sees_the_letter_with_more_contrast():
    from vissim.charts import optotype_tile
    from vissim.optics.eyes.measured.population import seen_image
    condition = PopulationCondition(4.0)
    results = sorted(evaluate_population(EYES, [condition]), key=lambda r: r.strehl)
    worst, best = (r.eye for r in (results[0], results[-1]))
    letter = optotype_tile("K", 0.1, arcmin_per_px=0.25, size_px=(64, 80), viewing_distance_m=6.0,
                           snap_to_pixels=False).pixels
    seen = [seen_image(e, condition, letter, 0.25) for e in (worst, best)]
    assert results[-1].strehl > results[0].strehl + 0.1 and seen[0].shape == letter.shape
    assert np.ptp(seen[1]) > np.ptp(seen[0])
    assert abs(seen[0].mean() - letter.mean()) < 0.01  # blur moves light, it does not make or lose it


def test_a_pupil_no_eye_has_is_refused():
    with pytest.raises(VissimInputError, match="pupil"):
        PopulationCondition(0.0)


def test_spectacles_of_the_eyes_own_refraction_leave_only_its_higher_orders():
    # The eye's minimum-RMS refraction at its pupil (Thibos et al. 2004 from c2 terms), carried to the
    # spectacle plane by each principal meridian's vergence, F / (1 + d F), d = 12 mm + the pupil's depth.
    from vissim.optics.eyes.report import eye_report
    from vissim.optics.rx.prescription import Prescription
    name = "jaeken-artal-2012:40:right"
    eye = build_eye(name, pupil_diameter_mm=4.0)
    front = eye_wavefront(eye, wavelength_nm=555.0).coefficients_um
    r2 = 2.0 ** 2
    m = -4 * math.sqrt(3) * front[(2, 0)] / r2
    j0, j45 = -2 * math.sqrt(6) * front[(2, 2)] / r2, -2 * math.sqrt(6) * front[(2, -2)] / r2
    cylinder = -2 * math.hypot(j0, j45)
    axis = math.degrees(0.5 * math.atan2(j45, j0)) % 180
    sphere = m - cylinder / 2
    depth_m = (12.0 + eye_report(eye, wavelength_nm=555.0).wavefront.entrance_pupil_position_mm) / 1000
    at_spectacles = [f / (1 + depth_m * f) for f in (sphere, sphere + cylinder)]
    rx = Prescription(at_spectacles[0], at_spectacles[1] - at_spectacles[0], axis)
    [best], [worn], [none] = (evaluate_population([parse_measured_eye(name)], [PopulationCondition(4.0, correction=c)], [10.0])
                              for c in ("sphero-cylinder", rx, "uncorrected"))
    assert worn.strehl == pytest.approx(best.strehl, rel=1e-6) and worn.mtf[0] == pytest.approx(best.mtf[0], rel=1e-6)
    assert none.strehl < 0.5 * best.strehl
    assert "wearing" in worn.condition.label and cylinder < -0.25  # the axis matters


def _hyperope_and_myope():
    """A foveal hyperope and a foveal myope of the data (3 mm, 555 nm, uncorrected M), with their M."""
    eyes = select_eyes("jaeken-artal-2012", subjects=range(1, 41), eyes=["right"])
    found = evaluate_population(eyes, [PopulationCondition(3.0, correction="uncorrected")])
    hyperope = max(found, key=lambda r: r.m_diopters)
    myope = min(found, key=lambda r: r.m_diopters)
    assert hyperope.m_diopters > 0.3 and myope.m_diopters < -0.3
    return hyperope, myope


def test_an_accommodating_eye_cancels_its_hyperopia_up_to_its_amplitude_and_no_myopia():
    """Oracle: accommodation is a plus lens at the pupil of power min(M, amplitude) for a hyperope (M > 0) and
    nothing for a myope: a hyperope with the amplitude to spare sees as it would wearing that sphere at the pupil
    (vertex 0 from its entrance pupil: spectacles of +M at minus the pupil's depth), a myope as uncorrected."""
    hyperope, myope = _hyperope_and_myope()
    m = hyperope.m_diopters
    accommodating = PopulationCondition(3.0, correction="accommodating", accommodation_amplitude_diopters=m + 1.0)
    short = PopulationCondition(3.0, correction="accommodating", accommodation_amplitude_diopters=0.5 * m)
    uncorrected = PopulationCondition(3.0, correction="uncorrected")
    fronts = {c: evaluate_population([hyperope.eye, myope.eye], [c], [10.0]) for c in (accommodating, short,
                                                                                          uncorrected)}
    seen_h = {c: fronts[c][0].strehl for c in fronts}
    assert seen_h[uncorrected] < seen_h[short] < seen_h[accommodating]
    assert fronts[accommodating][1].strehl == fronts[uncorrected][1].strehl  # the myope cannot accommodate away
    from vissim.optics.eyes.measured.measured_eye import BASE_EYE_MODEL
    from vissim.optics.eyes.models import eye_model
    from vissim.optics.eyes.paraxial import entrance_pupil_position_mm, mean_meridian_eye

    depth = entrance_pupil_position_mm(mean_meridian_eye(eye_model(BASE_EYE_MODEL)), 555.0)
    worn = PopulationCondition(3.0, correction=Prescription(m), vertex_mm=-depth)
    assert evaluate_population([hyperope.eye], [worn])[0].strehl == pytest.approx(seen_h[accommodating], rel=1e-12)
    # off axis the eye keeps the accommodation its fovea chose (the same plus sphere), not the periphery's own
    aside = [PopulationCondition(3.0, (10.0, 0.0), "accommodating", accommodation_amplitude_diopters=m + 1.0),
             PopulationCondition(3.0, (10.0, 0.0), Prescription(m), vertex_mm=-depth)]
    off_axis = evaluate_population([hyperope.eye], aside)
    assert off_axis[0].strehl == pytest.approx(off_axis[1].strehl, rel=1e-12)


@pytest.mark.parametrize("kwargs", [{"correction": "accommodating"},
                                    {"correction": "uncorrected", "accommodation_amplitude_diopters": 2.0},
                                    {"correction": "accommodating", "accommodation_amplitude_diopters": -1.0}])
def test_an_amplitude_goes_with_the_accommodating_correction_only(kwargs):
    with pytest.raises(VissimInputError, match="accommodation amplitude"):
        PopulationCondition(3.0, **kwargs)


@pytest.mark.parametrize("make, words", [
    (lambda: select_eyes("jaeken-artal-2012", subjects=[1, 1]), "names each subject once"),
    (lambda: select_eyes("jaeken-artal-2012", eyes=["right", "right"]), "names each eye once"),
    (lambda: population_conditions([3.0, 3.0], [(0.0, 0.0)], ["uncorrected"]), "given twice"),
    (lambda: population_conditions([3.0], [(0.0, 0.0)], ["uncorrected"], accommodation_amplitude_diopters=2.0),
     "goes with the accommodating correction only"),
])
def test_a_population_never_counts_an_eye_twice_nor_drops_an_amplitude(make, words):
    with pytest.raises(VissimInputError, match=words):
        make()
