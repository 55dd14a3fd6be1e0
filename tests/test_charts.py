"""LogMAR charts, tiles and the ``vissim chart`` command (vissim.charts, vissim.cli.chart)."""

from __future__ import annotations

import json
import math
import re
import zlib

import numpy as np
import pytest

from vissim.acuity import letter_height_arcmin, letter_height_mm
from vissim.charts import (
    ChartRow,
    ChartSpec,
    etdrs_chart_spec,
    layout_chart,
    logmar_steps,
    optotype_tile,
    render_chart_angular,
    render_chart_print,
    save_chart_pdf,
    single_letter_spec,
)
from vissim.cli import main
from vissim.errors import VissimInputError
from vissim.imageio import read_image
from vissim.optotypes import SLOAN_LETTERS, letter_coverage_window

THESIS = etdrs_chart_spec()  # LogMAR 1.0 .. -0.3 at 0.9144 m (Krueger 2015, section 4.1)


@pytest.fixture(scope="module")
def thesis_chart():
    return render_chart_angular(THESIS, 1.0)


def rows_of(boxes):
    out: dict[int, list] = {}
    for b in boxes:
        out.setdefault(b.row, []).append(b)
    return [sorted(out[k], key=lambda b: b.position) for k in sorted(out)]


def test_default_chart_has_the_thesis_rows_with_five_distinct_letters_each():
    assert [r.logmar for r in THESIS.rows] == pytest.approx([round(1.0 - 0.1 * i, 1) for i in range(14)])
    for row in THESIS.rows:
        assert len(row.letters) == 5 and len(set(row.letters)) == 5 and set(row.letters) <= set(SLOAN_LETTERS)
    assert etdrs_chart_spec() == THESIS  # the seeded choice is fixed
    assert etdrs_chart_spec(seed=7).rows != THESIS.rows
    assert THESIS.letter_seed is not None


@pytest.mark.parametrize("unit", ["arcmin", "mm"])
def test_etdrs_spacing(unit):
    # Ferris et al. 1982 (after Bailey & Lovie 1976): letter gap = letter width; the gap from a
    # row's baseline to the next row's top = the next row's letter height; margins >= largest width.
    layout = layout_chart(THESIS, arcmin_per_px=1.0)
    rows = rows_of(layout.letters)
    box = (lambda b: b.box_arcmin) if unit == "arcmin" else (lambda b: b.box_mm)
    heights = [box(r[0])[2] - box(r[0])[0] for r in rows]
    for row, h in zip(rows, heights):
        for a, b in zip(row, row[1:]):
            assert box(b)[1] - box(a)[3] == pytest.approx(h, rel=1e-9)
        assert all(box(b)[3] - box(b)[1] == pytest.approx(h, rel=1e-9) for b in row)
    for upper, lower, h_next in zip(rows, rows[1:], heights[1:]):
        assert box(lower[0])[0] - box(upper[0])[2] == pytest.approx(h_next, rel=1e-9)
    size = (np.asarray(layout.shape_px) * layout.arcmin_per_px) if unit == "arcmin" else layout.page_size_mm
    flat = [box(b) for b in layout.letters]
    h_max = max(heights)
    assert min(b[0] for b in flat) >= h_max - 1e-9 and min(b[1] for b in flat) >= h_max - 1e-9
    assert size[0] - max(b[2] for b in flat) >= h_max - 1e-9 and size[1] - max(b[3] for b in flat) >= h_max - 1e-9


def test_letter_heights_follow_eq_4_1():
    # Thesis Eq. 4.1 (chart at 914.4 mm): LogMAR 0 is 1.330 mm; a 6 m chart's LogMAR 0 is 8.727 mm.
    layout = layout_chart(THESIS, dpi=360)
    for b in layout.letters:
        assert b.box_mm[2] - b.box_mm[0] == pytest.approx(letter_height_mm(b.logmar, 0.9144), rel=1e-12)
        assert b.box_px[2] - b.box_px[0] == pytest.approx(letter_height_mm(b.logmar, 0.9144) * 360 / 25.4)
    zero = [b for b in layout.letters if b.logmar == 0.0][0]
    assert zero.box_mm[2] - zero.box_mm[0] == pytest.approx(1.330, abs=5e-4)
    far = layout_chart(single_letter_spec("H", 0.0, viewing_distance_m=6.0), dpi=360).letters[0]
    assert far.box_mm[2] - far.box_mm[0] == pytest.approx(8.727, abs=5e-4)


def test_angular_chart_at_1_arcmin_per_px_makes_logmar_0_five_px_tall(thesis_chart):
    for b in thesis_chart.letters:
        assert b.height_px == pytest.approx(letter_height_arcmin(b.logmar))
    assert [b.height_px for b in thesis_chart.letters if b.logmar == 0.0] == pytest.approx([5.0] * 5)
    assert thesis_chart.pixels.dtype == np.float32 and thesis_chart.pixels.shape == (517, 550)


def test_every_box_holds_all_of_its_letters_ink_and_no_other(thesis_chart):
    spec = thesis_chart.spec
    ink = (spec.background_reflectance - thesis_chart.pixels.astype(float)) / (
        spec.background_reflectance - spec.letter_reflectance
    )
    owner = np.full(ink.shape, -1)
    for i, b in enumerate(thesis_chart.letters):
        t, l, bot, r = b.box_px
        window = (slice(math.floor(t), math.ceil(bot)), slice(math.floor(l), math.ceil(r)))
        assert np.all(owner[window] == -1), f"box {i} overlaps another"
        owner[window] = i
        _, _, solo = letter_coverage_window(b.letter, b.height_px, ink.shape, b.center_rc)
        assert ink[window].sum() == pytest.approx(solo.sum(), rel=1e-5, abs=1e-3)
    assert np.abs(ink[owner == -1]).max() < 1e-6  # no ink outside every box


def test_sidecar_is_json_safe_and_lists_every_letter(thesis_chart):
    side = json.loads(json.dumps(thesis_chart.sidecar(), allow_nan=False))
    assert len(side["letters"]) == 70 and side["shape_px"] == [517, 550]
    first = side["letters"][0]
    assert first["snellen_20ft"] == "20/200" and first["box_px"] == {"top": 50.0, "left": 50.0,
                                                                     "bottom": 100.0, "right": 100.0}
    assert side["paper_reflectance"] == 0.9 and side["ink_reflectance"] == 0.04


@pytest.mark.parametrize(("polarity", "background", "letters"),
                         [("black-on-white", 0.9, 0.04), ("white-on-black", 0.04, 0.9)])
def test_polarity_swaps_paper_and_ink(polarity, background, letters):
    tile = optotype_tile("H", 1.0, polarity=polarity)
    assert tile.pixels[0, 0] == pytest.approx(background)
    t, l, _, _ = (int(v) for v in tile.letters[0].box_px)
    assert tile.pixels[t + 5, l + 5] == pytest.approx(letters)  # inside the left stem


def test_thesis_tile_is_113_wide_133_tall_with_the_letter_centred():
    # ERRATA item 8: 113 x 133 px at 1 arcmin/px (1.88 x 2.22 deg).
    tile = optotype_tile("C", 1.0)
    assert tile.pixels.shape == (133, 113)
    (row_c, col_c), box = tile.letters[0].center_rc, tile.letters[0].box_px
    assert abs(row_c - 66.5) <= 0.5 and abs(col_c - 56.5) <= 0.5
    assert all(float(v).is_integer() for v in box)  # snapped: a 50 px letter has crisp edges
    ink = (0.9 - tile.pixels.astype(float)) / (0.9 - 0.04)
    c_area = ink.sum() / 50**2 * 25  # design units^2
    assert 0.75 * math.pi * 4 < c_area < math.pi * 4
    with pytest.raises(VissimInputError, match="do not fit"):
        optotype_tile("C", 1.5)


def test_print_raster_has_physical_size():
    spec = single_letter_spec("Z", 0.5)
    chart = render_chart_print(spec, dpi=360)
    h_mm = letter_height_mm(0.5, 0.9144)
    assert chart.letters[0].height_px == pytest.approx(h_mm * 360 / 25.4)
    assert chart.pixels.shape == (math.ceil(3 * h_mm * 360 / 25.4), math.ceil(3 * h_mm * 360 / 25.4))
    assert chart.mm_per_px == pytest.approx(25.4 / 360)


def test_pdf_page_is_the_chart_size_and_is_not_overwritten(tmp_path):
    spec = etdrs_chart_spec((0.3, 0.2), letters="NCKZO")
    path = save_chart_pdf(spec, tmp_path / "chart.pdf")
    data = path.read_bytes()
    assert data.startswith(b"%PDF")
    box = [float(v) for v in re.search(rb"/MediaBox\s*\[\s*([^\]]+)\]", data).group(1).split()]
    height_mm, width_mm = layout_chart(spec, dpi=72).page_size_mm
    assert box[2:] == pytest.approx([width_mm / 25.4 * 72, height_mm / 25.4 * 72], abs=0.01)
    content = b"".join(zlib.decompress(m) for m in re.findall(rb"stream\r?\n(.*?)endstream", data, re.S))
    assert b"\nf\n" in content and b"f*" not in content  # nonzero fill: each letter is one seamless union
    with pytest.raises(VissimInputError, match="already exists"):
        save_chart_pdf(spec, path)
    save_chart_pdf(spec, path, overwrite=True)


@pytest.mark.parametrize(
    ("make", "needle"),
    [
        (lambda: ChartSpec((ChartRow(0.0, "NCKZO"),), polarity="grey"), "polarity"),
        (lambda: ChartSpec((ChartRow(0.0, "NCKZO"),), ink_reflectance=0.95), "reflectance"),
        (lambda: ChartSpec((ChartRow(0.0, "NCKZO"),), viewing_distance_m=-1), "viewing distance"),
        (lambda: ChartRow(0.0, "NCKEO"), "'E'"),
        (lambda: ChartRow(math.nan, "N"), "LogMAR"),
        (lambda: logmar_steps(1.0, 0.05), "steps"),
        (lambda: etdrs_chart_spec((1.0, 0.8), letters="NCKZO,HVORS"), "rows"),
        (lambda: render_chart_angular(THESIS, 0.0), "arcmin per pixel"),
    ],
)
def test_bad_chart_input_raises(make, needle):
    with pytest.raises(VissimInputError, match=needle):
        make()


def test_cli_writes_image_and_letter_boxes_and_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "chart.exr"
    args = ["chart", "--logmar-range", "0.5,0.3", "--letters", "NCKZO", "-o", str(out)]
    assert main(args) == 0
    printed = capsys.readouterr().out.strip().splitlines()
    assert len(printed) == 2 and all(line.startswith("wrote ") for line in printed)
    image = read_image(out)
    side = json.loads((tmp_path / "chart.exr.letters.json").read_text())
    assert image.pixels.shape == tuple(side["shape_px"]) and len(side["letters"]) == 15
    assert image.provenance["inputs"]["command"] == "vissim chart"
    before = out.read_bytes()
    assert main(args) == 2
    assert "already exists" in capsys.readouterr().err and out.read_bytes() == before
    assert main([*args, "--overwrite"]) == 0


def test_cli_tile_print_and_bad_letter(tmp_path, capsys):
    assert main(["chart", "--tile", "--letter", "K", "--logmar", "1.0", "-o", str(tmp_path / "k.exr")]) == 0
    assert read_image(tmp_path / "k.exr").pixels.shape == (133, 113)
    assert main(["chart", "--print", "--logmar", "0.0", "--letters", "HVO", "-o", str(tmp_path / "p.pdf")]) == 0
    assert main(["chart", "--print", "--logmar", "0.0", "--letter", "S", "--dpi", "100",
                 "-o", str(tmp_path / "p.png")]) == 0
    for name in ("p.pdf", "p.pdf.letters.json", "p.png", "p.png.json", "p.png.letters.json"):
        assert (tmp_path / name).is_file(), name
    capsys.readouterr()
    assert main(["chart", "--letters", "NCKEO", "-o", str(tmp_path / "bad.exr")]) == 2
    err = capsys.readouterr().err
    assert "'E'" in err and "C D H K N O R S V Z" in err and not (tmp_path / "bad.exr").exists()
