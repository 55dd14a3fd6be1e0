"""The report reads on its own: a small campaign's tables.md and report.html, parsed.

A campaign with the stand-in bench (no Mitsuba): a sweep with a no-lens member and a +1 D lens,
and one astigmatic item; the wave bench on. Oracles: the campaign file's own values (letters,
LogMAR, lenses), metrics.csv (every row the tables summarise), 10 log10(2) for a perfect
simulation, and the sRGB transfer function for the colour bars' ticks.
"""

import csv
import math
import re
from html.parser import HTMLParser

import matplotlib.pyplot as plt
import numpy as np
import pytest
from fake_bench import fake_render, write_campaign

from vissim.imageio import srgb_encode
import vissim.validation.dslr.report as report
from vissim.validation.dslr.report_words import column_title
from vissim.validation.engine.report import load_results, write_report
from vissim.validation.engine.figures import RADIANCE_LABEL, display_norm, radiance_colorbar, scale_bar_arcmin
from vissim.validation.engine.summary import PERFECT_MARGIN_DB, summary_notes
from vissim.validation.engine.runner import run_campaign
from vissim.validation.dslr.wave_bench import WAVE_BENCH_NOTE
from vissim.validation.dslr.wave_bench_report import RESIDUAL_COLUMNS

CAMPAIGN = """
[campaign]
name = "reads"
description = "Checks that the report `reads` on its own"
spp = 4
seeds = [1, 2]
tile_px = [64, 64]
arcmin_per_px = 1.0
simulations = ["wave", "geometric"]
inputs = ["render", "synthetic"]

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


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("reads")
    run = folder / "run"
    run_campaign(write_campaign(folder, CAMPAIGN, "reads.toml"), run, render=fake_render, show_progress=False)
    write_report(run)
    return run


@pytest.fixture(scope="module")
def tables(run_dir):
    return (run_dir / "tables.md").read_text()


@pytest.fixture(scope="module")
def page(run_dir):
    return (run_dir / "report.html").read_text()


def section(text: str, heading: str) -> str:
    return text.split(f"### {heading}")[1].split("\n### ")[0]


def table_rows(text: str) -> list[list[str]]:
    return [[c.strip() for c in line.strip().strip("|").split("|")] for line in text.splitlines()
            if line.startswith("|") and not line.startswith("|---")]


def metrics(run_dir) -> list[dict]:
    with open(run_dir / "metrics.csv") as handle:
        return list(csv.DictReader(handle))


def test_generated_names_put_logmar_and_the_trial_lens_in_words(run_dir):
    names = [r["configuration"]["name"] for r in load_results(run_dir)]
    # the campaign file: K at LogMAR 0.7 with spheres 0 and +1 D
    assert "myopia: K LogMAR 0.7 black, no lens" in names
    assert "myopia: K LogMAR 0.7 black, trial lens +1.00 DS" in names
    for name in names:  # no bare signed number (the old "K +0.7 black +1.00 DS") before a lens power
        assert not re.search(r"\b[A-Z] [+-]\d\.\d\b", name), name


def test_a_reused_item_takes_the_campaign_name(run_dir, tmp_path):
    # names are not part of an item's key: renaming a configuration reuses its result under the new name
    import json
    import shutil

    copy = tmp_path / "run"
    shutil.copytree(run_dir, copy)
    record = json.loads((copy / "campaign.json").read_text())
    record["configurations"][0]["name"] = "renamed"
    (copy / "campaign.json").write_text(json.dumps(record))
    assert load_results(copy)[0]["configuration"]["name"] == "renamed"


def test_tables_say_which_power_is_the_trial_lens_and_which_the_camera_rx(run_dir, tables):
    rows = table_rows(section(tables, "Scores per configuration (dB over the noise floor)"))
    header, body = rows[0], {r[0]: r for r in rows[1:]}
    column = header.index("trial lens(es) → camera Rx")
    powers = {name: row[column].split(" → ") for name, row in body.items()}
    wave = {(m["configuration"]): m for m in metrics(run_dir) if m["simulation"] == "wave" and m["input"] == "render"
            and m["lenses"] != "no lens"}
    assert set(wave) == set(body)  # the configurations with a lens; those without are judged apart
    for name, m in wave.items():
        assert powers[name] == [m["lenses"], m["camera_prescription"]]
    lens, rx = powers["myopia: K LogMAR 0.7 black, trial lens +1.00 DS"]
    assert lens == "+1.00 DS"
    # a +1 D trial lens makes the camera myopic: its correcting Rx is about -1 D
    assert rx.startswith("-0.9")
    assert powers["cylinder"][0] == "+1.50 -1.50 x 180"  # the campaign's +1.50 cylinder at 90, in minus cylinder
    # fewer columns, named in words, not code identifiers
    assert len(header) <= 7 and not any("_" in h or " / " in h for h in header)


def test_the_no_lens_configuration_is_judged_by_one_grey_level_not_its_floor(run_dir, tables):
    rows = table_rows(section(tables, "Configurations without a lens"))
    assert [r[0] for r in rows[1:]] == ["myopia: K LogMAR 0.7 black, no lens"]
    psnr = {(m["simulation"], m["input"]): float(m["psnr_db"]) for m in metrics(run_dir)
            if m["configuration"] == "myopia: K LogMAR 0.7 black, no lens" and m["reference"] != WAVE_BENCH_NOTE}
    for column, cell in zip(rows[0][1:-1], rows[1][1:-1]):
        key = next(k for k in psnr if report._short_words(k) == column)
        assert cell == f"{psnr[key]:.1f}"
    judged = [v for (s, _), v in psnr.items() if s in report.LIBRARY_SIMULATIONS]
    assert rows[1][-1].startswith("yes" if min(judged) >= 20 * math.log10(255) else "no")


def test_figure_headings_say_which_power_is_the_trial_lens_and_which_the_camera_rx(run_dir):
    result = next(r for r in load_results(run_dir) if r["lens_label"] == "+1.00 DS")
    wave = next(c for c in result["comparisons"] if c["simulation"] == "wave")
    title = column_title(result, wave)
    assert "LogMAR 0.7" in title and "trial lens +1.00 DS" in title
    assert f"camera Rx {wave['setup']['camera_prescription']}" in title
    bare = next(r for r in load_results(run_dir) if r["lens_label"] == "no lens")
    # the heading says the lens as the configuration's name does (one phrase: schema.trial_lens_phrase)
    for r in (result, bare):
        assert r["configuration"]["name"].endswith(", " + column_title(r).splitlines()[1])
    assert column_title(bare, bare["comparisons"][0]).splitlines()[1] == "no lens"


def test_the_residuals_are_a_table_with_a_row_per_group(tables):
    text = section(tables, "Residuals against the wave bench, explained")
    rows = table_rows(text)
    assert rows[0] == ["group (configurations)", *RESIDUAL_COLUMNS]
    assert sorted(r[0] for r in rows[1:]) == ["cylinder (1)", "myopia (2)"]
    assert all(len(r) == len(rows[0]) for r in rows)
    assert not [line for line in text.splitlines() if line.startswith("- ")]


def test_html_shows_no_markdown_backticks(page):
    assert "`" not in page
    assert "<code>traced_rays</code>" in page and "<code>reads</code>" in page  # the description's span too


def test_no_issue_numbers(tables, page):
    for text in (tables, page):
        assert not re.search(r"\b[Ii]ssues? \d+|#\d+\b", text)


def test_no_lens_rows_are_marked_explained_and_left_out_of_a_second_table(run_dir, tables):
    summary = table_rows(section(tables, "Summary: median PSNR minus the noise floor (dB)"))
    assert "myopia (2, 1 without a lens)¹" in summary[0] and "cylinder (1)" in summary[0]
    notes = section(tables, "Reading the summary: above +3 dB, and the configurations without a lens")
    assert "count in their groups' medians" in notes and "floor is high" in notes
    rows = table_rows(section(tables, "Summary of the groups with no-lens configurations, over those with lenses only"))
    assert rows[0][1:] == ["myopia (1)"]
    # oracle: metrics.csv, the +1 D row alone
    lens_row = {(m["simulation"], m["input"]): float(m["psnr_db"]) - float(m["noise_floor_psnr_db"])
                for m in metrics(run_dir) if m["configuration"] == "myopia: K LogMAR 0.7 black, trial lens +1.00 DS"
                and m["reference"] != WAVE_BENCH_NOTE}
    assert len(rows) - 1 == len([k for k in lens_row if k[0] != "traced_rays"])
    for words, cell in rows[1:]:
        key = next(k for k in lens_row if report.column_words(k) == words)
        assert cell == f"{lens_row[key]:+.1f}"


def _rows(margins: list[float], lenses: str = "+1.00 DS") -> list[dict]:
    return [{"configuration": f"g: c{k}", "simulation": "geometric", "input": "synthetic", "lenses": lenses,
             "psnr_db": 40.0 + m, "noise_floor_psnr_db": 40.0} for k, m in enumerate(margins)]


def test_a_score_above_three_db_is_explained_with_the_runs_numbers():
    assert PERFECT_MARGIN_DB == pytest.approx(10 * math.log10(2))
    outside = {**_rows([3.5])[0], "configuration": "g: other", "simulation": "traced_rays"}  # not a summary column
    text = summary_notes(_rows([2.5, 3.31]) + [outside], [("geometric", "synthetic")])
    # 10**(3.31/10) = 2.143: the floor's MSE over the simulation's; 14 % beyond 2
    assert "10·log10(2) = +3.01 dB" in text
    assert "This run's highest is +3.31 dB (g: c1, geometric / synthetic)" in text
    assert "2.14 times the simulation's instead of 2" in text and "14 % more noise energy" in text
    assert "no configuration with lenses scores above" in summary_notes(_rows([2.5, 2.9]), [("geometric", "synthetic")])


def test_the_synthetic_inputs_get_figures(run_dir, tables, page):
    for simulation, words in (("wave", "wave optics"), ("geometric", "ray optics")):
        name = f"figure_{simulation}_synthetic.png"
        assert (run_dir / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert f"]({name})" in tables
        assert f"{words} on the drawn chart</h2>" in page and f"{simulation} simulation on the" not in page


class Images(HTMLParser):
    def __init__(self):
        super().__init__()
        self.alts = []

    def handle_starttag(self, tag, attrs):
        if tag == "img":
            self.alts.append(dict(attrs).get("alt"))


def test_every_image_has_alt_text_saying_what_it_shows(run_dir, tables, page):
    images = Images()
    images.feed(page)
    markdown = re.findall(r"!\[([^\]]*)\]\((figure_[^)]+)\)", tables)
    assert len(images.alts) == len(markdown) == len(list(run_dir.glob("figure_*.png"))) >= 6
    for alt in images.alts + [alt for alt, _ in markdown]:
        assert alt and len(alt) > 60, alt
    tiles = next(alt for alt, name in markdown if name == "figure_wave_synthetic.png")
    assert "Rows:" in tiles and "myopia: K LogMAR 0.7 black, trial lens +1.00 DS" in tiles


def test_grey_colour_bars_show_relative_radiance_at_display_gamma_with_even_ticks():
    fig, ax = plt.subplots()
    bar = fig.colorbar(ax.imshow(np.linspace(0, 1, 16).reshape(4, 4), cmap="gray", norm=display_norm()))
    radiance_colorbar(bar)
    label = bar.ax.get_ylabel()
    assert " ".join(label.split()) == RADIANCE_LABEL == "relative radiance, display gamma"
    # ticks at linear radiance whose sRGB codes are evenly spaced: even steps on the bar
    codes = srgb_encode(np.asarray(bar.get_ticks()))
    np.testing.assert_allclose(np.diff(codes), 0.25, atol=1e-9)
    plt.close(fig)


@pytest.fixture
def drawn(run_dir, monkeypatch):
    """The matplotlib figure of the wave simulation's tiles, kept open."""
    kept = []
    monkeypatch.setattr(report, "png_bytes", lambda fig: kept.append(fig) or b"")
    report._figure(load_results(run_dir), run_dir, "wave", "synthetic")
    yield kept[0]
    plt.close(kept[0])


def test_tile_figures_label_grey_bars_radiance_never_reflectance(drawn):
    labels = [ax.get_ylabel() + ax.get_xlabel() for ax in drawn.axes]
    assert any("relative radiance" in label and "display gamma" in label for label in labels)
    assert not any("reflectance" in label for label in labels)


def test_letter_tiles_carry_an_angular_scale_bar(drawn):
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    bars = [a for ax in drawn.axes for a in ax.artists if isinstance(a, AnchoredSizeBar)]
    assert len(bars) == 3  # one per column (configuration), on the truth tile
    arcmin_per_px = 1.0  # the campaign: 64 px tiles at 1 arcmin/px
    expected = scale_bar_arcmin(64, arcmin_per_px)
    assert expected == 20.0  # the longest round length within 40 % of 64 arcmin
    for bar in bars:
        rectangle = bar.size_bar.get_children()[0]
        tile = bar.axes.get_images()[0]  # the row's tiles share one axes: its data units per tile pixel
        left, right, _, _ = tile.get_extent()
        per_px = (right - left) / tile.get_array().shape[1]
        assert rectangle.get_width() / per_px * arcmin_per_px == pytest.approx(expected)
        assert bar.txt_label.get_text() == "20′"
    assert "scale bars 20 arcmin" in drawn._suptitle.get_text()
