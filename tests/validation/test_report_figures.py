"""The report's optics figures: the wave PSF on a log scale, its MTF against the diffraction limit,
through focus; written with provenance, linked from tables.md and shown in report.html."""

import json

import matplotlib.pyplot as plt
import numpy as np
import pytest
from fake_bench import fake_render, write_campaign

from vissim.optics.rx.trial_lens import entrance_pupil_diameter_mm, trial_lens_effect
from vissim.units import arcmin_to_rad, cyc_per_rad_to_cyc_per_deg
from vissim.optics.blur.resample import SUBPIXELS_PER_PX
from vissim.validation.dslr.optics_figures import (THROUGH_FOCUS_STEPS_D, case_psf, mtf_curves, mtf_figure_of,
                                              optics_cases, psf_figure_of, recorded_psf, sampling_label)
from vissim.validation.engine.loader import load_campaign
from vissim.validation.engine.report import load_results, write_report
from vissim.validation.dslr.renders import build_dslr
from vissim.validation.engine.runner import run_campaign

SMALL = """
[campaign]
name = "figures"
spp = 4
seeds = [1, 2]
tile_px = [64, 64]
simulations = ["wave"]
inputs = ["synthetic"]
wave_truth = false

[[sweep]]
name = "myopia"
letter = ["K"]
logmar = [0.7]
lens = [0.0, 1.0]

[[item]]
name = "cylinder"
letter = "N"
logmar = 0.7
lenses = [{ cylinder_diopters = 1.5, axis_deg = 90 }]
"""

FIGURES = ("figure_psf.png", "figure_mtf.png", "figure_through_focus.png")


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("figures")
    run = folder / "run"
    run_campaign(write_campaign(folder, SMALL, "figures.toml"), run, render=fake_render, show_progress=False)
    write_report(run)
    return run


@pytest.fixture(scope="module")
def cases(run_dir):
    return optics_cases(load_results(run_dir), run_dir, json.loads((run_dir / "campaign.json").read_text()))


def test_one_case_per_group_with_lenses_and_the_optics_of_its_bench(run_dir, cases):
    # Oracle: the campaign above (the myopia sweep's only lens is +1 D; the cylinder item is its
    # own group) and the bench's ray-transfer matrices (`trial_lens_effect`, as fake_bench uses),
    # not the power matrix result.json records, which optics_cases reads.
    campaign = load_campaign(run_dir.parent / "figures.toml")
    configurations = {c.name: c for c in campaign.configurations}
    picked = {c.group: configurations[c.configuration] for c in cases}
    assert sorted(picked) == ["cylinder", "myopia"]
    assert [(l.sphere_diopters, l.cylinder_diopters) for l in picked["myopia"].lenses] == [(1.0, 0.0)]
    assert picked["cylinder"].name == "cylinder"
    settings = campaign.settings
    for case in cases:
        bench = build_dslr(picked[case.group], settings).bench
        expected = trial_lens_effect(bench.trial_lens_setup()).camera_prescription
        got = case.prescription
        # result.json keeps the power matrix as numbers, so the figure's optics are the item's to round-off
        np.testing.assert_allclose(got.power_matrix(), expected.power_matrix(), rtol=0, atol=1e-12)
        expected_pupil = entrance_pupil_diameter_mm(settings.focal_length_mm, picked[case.group].f_number)
        assert case.pupil_diameter_mm == pytest.approx(expected_pupil)
        assert case.wavelength_nm == settings.wavelength_nm
        assert case.psf_arcmin_per_px == pytest.approx(settings.arcmin_per_px / SUBPIXELS_PER_PX)


def test_the_psf_figures_read_the_psf_the_item_used(cases, tmp_path):
    """The PSF and MTF panels show the PSF the wave simulation used, as the item saved it: equal to the PSF
    its recorded numbers give (to float32 storage), and what the file holds (a delta put there is read back)."""
    from dataclasses import replace

    from vissim.imageio import write_image

    for case in cases:
        stored, computed = recorded_psf(case), case_psf(case)
        assert case.psf_file.name == "psf_wave.exr" and stored.arcmin_per_px == computed.arcmin_per_px
        np.testing.assert_allclose(stored.data, computed.data, rtol=0, atol=1e-6 * computed.data.max())
    delta = np.zeros((9, 9), np.float32)
    delta[4, 4] = 1.0
    write_image(tmp_path / "psf_wave.exr", delta)
    assert recorded_psf(replace(cases[0], psf_file=tmp_path / "psf_wave.exr")).data[4, 4] == 1.0


def test_figures_are_written_with_provenance_and_linked(run_dir, cases):
    tables = (run_dir / "tables.md").read_text()
    page = (run_dir / "report.html").read_text()
    for name in FIGURES:
        png = run_dir / name
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        sidecar = json.loads((run_dir / f"{name}.json").read_text())
        assert sidecar["inputs"]["campaign"] == "figures" and sidecar["figure"]
        assert [o["camera_prescription"] for o in sidecar["optics"]] == [c.prescription.format(4) for c in cases]
        assert f"]({name})" in tables  # a Markdown image link beside the tables
        assert sidecar["figure"] in page
    assert page.count("data:image/png;base64,") == len(list(run_dir.glob("figure_*.png")))


def test_log_psf_panels_state_the_sampling_they_show(cases):
    psfs = [case_psf(case) for case in cases]
    fig = psf_figure_of(cases, psfs)
    try:
        for ax, case, psf in zip(fig.axes, cases, psfs):
            assert psf.arcmin_per_px == pytest.approx(case.psf_arcmin_per_px)
            label = ax.get_xlabel()
            assert sampling_label(psf) in label
            assert f"{psf.arcmin_per_px:.3g} arcmin/px" in label and f"{case.pupil_diameter_mm:.3g} mm pupil" in label
            image = ax.get_images()[0]
            left, right, bottom, top = image.get_extent()
            rows, cols = image.get_array().shape
            # the axes are in arcmin at the PSF's own sampling, centred on the chief ray, +y up
            assert (right - left) / cols == pytest.approx(psf.arcmin_per_px)
            assert (top - bottom) / rows == pytest.approx(psf.arcmin_per_px)
            assert left == pytest.approx(-right) and top > bottom
            assert image.get_array().max() == pytest.approx(0.0)  # log10 of the peak
    finally:
        plt.close(fig)


def test_mtf_plotted_is_below_the_diffraction_limit(cases):
    psfs = [case_psf(case) for case in cases]
    fig = mtf_figure_of(cases, psfs)
    try:
        for ax, psf in zip(fig.axes, psfs):
            lines = {line.get_label(): line for line in ax.get_lines()}
            limit = lines["diffraction limit"]
            # The PSF is normalised over its field (energy E inside), and the plotted MTF has the
            # pixel's sinc divided out: |OTF / sinc| <= (diffraction + (1 - E) / sinc) / E, the
            # light outside the field changing the OTF by at most 1 - E (Goodman, Fourier Optics §6.3).
            e = psf.energy_in_field

            def bound(freq, limit):
                pixel = np.sinc(np.asarray(freq) / cyc_per_rad_to_cyc_per_deg(1.0) * arcmin_to_rad(psf.arcmin_per_px))
                return (limit + (1.0 - e) / pixel) / e + 1e-9

            for label in ("along x (horizontal)", "along y (vertical)"):
                np.testing.assert_array_equal(lines[label].get_xdata(), limit.get_xdata())
                assert np.all(lines[label].get_ydata() <= bound(limit.get_xdata(), limit.get_ydata())), label
            curves = mtf_curves(psf)
            radial_limit = bound(curves["radial_frequency_cyc_per_deg"], curves["radial_diffraction"])
            assert np.all(curves["radial"] <= radial_limit)
            np.testing.assert_allclose(lines["radial mean"].get_ydata(), curves["radial"])
            assert curves["horizontal"][0] == pytest.approx(1.0)
            # defocused: well under the limit at a tenth of the cutoff
            tenth = np.searchsorted(curves["frequency_cyc_per_deg"], 0.1 * float(curves["cutoff_cyc_per_deg"]))
            assert curves["radial"][tenth] < 0.5 * curves["radial_diffraction"][tenth]
    finally:
        plt.close(fig)


def test_through_focus_steps_move_the_sphere_of_the_prescription(cases):
    myope = next(c for c in cases if c.group == "myopia")  # a +1 D lens: the camera's prescription is about -1 DS
    assert myope.prescription.sphere_diopters == pytest.approx(-1.0, abs=0.05)
    assert 1.0 in THROUGH_FOCUS_STEPS_D
    peaks = [case_psf(myope, myope.arcmin_per_px, step).data.max() for step in (-1.0, 0.0, 1.0)]
    assert peaks[0] < peaks[1] < peaks[2]  # +1 D brings it to plano: the sharpest


def test_a_failing_optics_figure_leaves_the_rest_of_the_report(run_dir, tmp_path, monkeypatch, caplog):
    # A run folder whose synthetic chart cannot be read: the figures are skipped with a warning,
    # the tables and the other figures are still written.
    import shutil

    import vissim.validation.dslr.report as report

    def unreadable(*args, **kwargs):
        raise OSError("synthetic.exr: unreadable")

    copy = tmp_path / "run"
    shutil.copytree(run_dir, copy)
    for name in FIGURES:
        (copy / name).unlink()
    monkeypatch.setattr(report, "optics_figure", unreadable)
    write_report(copy)
    assert (copy / "tables.md").exists() and (copy / "report.html").exists()
    assert not any((copy / name).exists() for name in FIGURES)
    from vissim.validation.dslr.optics_figures import OPTICS_FIGURES

    for name in OPTICS_FIGURES:  # each figure skipped on its own, named
        assert f"optics figure {name!r} was skipped (OSError" in caplog.text


@pytest.mark.parametrize("n_panels, long_names", [(1, None), (3, None), (3, "words"), (3, "one word")])
def test_fixed_layouts_keep_every_label_inside_the_figure_and_off_other_panels(cases, run_dir, n_panels, long_names):
    """The optics figures are laid out at fixed places (inches), not by matplotlib's layout engine: every text
    the figures draw lies inside the figure; no panel's labels overlap another panel or colour bar; no title
    overlaps another, configuration and group names as long as a name may be (`MAX_NAME_CHARS`), in words or in
    one word, wrapped to their panel, included (0.5 px: window extents are rounded to whole pixels)."""
    from dataclasses import replace

    from vissim.checks import MAX_NAME_CHARS
    from vissim.validation.dslr.optics_figures import through_focus_figure_of

    chosen = (cases * 3)[:n_panels]
    if long_names:
        word = "configuration with a long name " if long_names == "words" else "configuration_with_a_long_name_"
        chosen = [replace(case, configuration=(f"{i}_" + word * 4)[:MAX_NAME_CHARS],
                          group=(f"{i}_" + word.replace("configuration", "group") * 5)[:MAX_NAME_CHARS])
                  for i, case in enumerate(chosen)]
        assert all(len(case.configuration) == len(case.group) == MAX_NAME_CHARS for case in chosen)
    psfs = [case_psf(case) for case in chosen]
    for fig in (psf_figure_of(chosen, psfs), mtf_figure_of(chosen, psfs), through_focus_figure_of(chosen)):
        try:
            assert fig.get_layout_engine() is None
            fig.canvas.draw()
            renderer = fig.canvas.get_renderer()
            frame = fig.bbox
            areas = [ax.get_window_extent(renderer) for ax in fig.axes]  # panels and colour bars
            titles = [t.get_window_extent(renderer) for t in [*fig.texts, *(ax.title for ax in fig.axes)]
                      if t.get_text()]
            for box in [ax.get_tightbbox(renderer) for ax in fig.axes] + titles:
                assert frame.x0 - 0.5 <= box.x0 and box.x1 <= frame.x1 + 0.5, (box, frame)
                assert frame.y0 - 0.5 <= box.y0 and box.y1 <= frame.y1 + 0.5, (box, frame)
            for i, ax in enumerate(fig.axes):  # an axes' labels off every other axes
                labels = ax.get_tightbbox(renderer)
                assert not any(labels.overlaps(area) for j, area in enumerate(areas) if j != i), ax
            for i, title in enumerate(titles):  # a title off every axes and every other title
                assert not any(title.overlaps(area) for area in areas), title
                assert not any(title.overlaps(other) for other in titles[i + 1:]), title
        finally:
            plt.close(fig)
