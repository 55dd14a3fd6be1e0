"""Every value-taking option of every command, at bad values: a result or one error line (slow).

The companion of test_bad_input.py's hypothesis walk, over all commands including the renders
and the ATV experiment: each option in turn gets zero, negative, NaN, infinite, huge, tiny and
non-numeric values on top of a small working invocation.  Run with ``-m slow`` (about 5 min).
"""

import argparse
import shutil

import numpy as np
import pytest

from vissim.cli import build_parser, main
from vissim.cli._parser import Number
from vissim.imageio import write_image
from vissim.provenance import make_provenance

ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]
VALUES = ["0", "-1", "nan", "inf", "-inf", "1e300", "1e-300", "abc", ""]
BASES = {
    ("rx",): ["rx", "-2.00 -1.25 x 180", "--pupil-mm", "6", "--json"],
    ("trial-lens",): ["trial-lens", "--sphere", "2"],
    ("eye",): ["eye", "--eye-model", "navarro-1985", "--pupil-mm", "3", "--mtf-cyc-per-deg", "10", "--json"],
    ("bench", "wavefront"): ["bench", "wavefront", "--sphere", "2"],
    ("psf",): ["psf", "--rx", "-2", "--pupil-mm", "3", "--size", "161", "-o", "{out}/p.exr"],
    ("chart",): ["chart", "--logmar", "1", "-o", "{out}/c.exr"],
    ("blur",): ["blur", "{chart}", "-o", "{out}/b.exr", "--rx", "-2", "--pupil-mm", "3"],
    ("blur-depth",): ["blur-depth", "{chart}", "{depth}", "-o", "{out}/b.exr", "--rx", "-2", "--pupil-mm", "3"],
    ("render", "bench"): ["render", "bench", "--spp", "4", "--size", "21x21", "-o", "{out}/r.exr"],
    ("render", "atv"): ["render", "atv", "--rays", "20000", "-o", "{out}/a.exr"],
    ("render", "depth"): ["render", "depth", str(ROOT / "scenes/depth_panels.toml"), "--spp", "2", "-o", "{out}/d.exr"],
    ("atv", "analyze"): ["atv", "analyze", str(ROOT / "validation/atv"), "-o", "{out}/atv"],
    ("atv", "run"): ["atv", "run", "--observer", "simulated", "-o", "{out}/run.json"],
    ("atv", "simulate"): ["atv", "simulate", "--pupil-mm", "4", "--rx", "+1", "--lenses", "-1,0,1,2,3", "-o", "{out}/sim"],
    ("fit-rx",): ["fit-rx", "{fit_image}", "--reference", "{fit_reference}", "--pupil-mm", "3.6", "--mode", "geometric",
                  "--magnification", "none", "--json", "-o", "{out}/fit.json"],
}


def _options(path):
    parser = build_parser()
    for name in path:
        parser = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[name]
    return [(a.option_strings[-1], a.type in (int, float) or isinstance(a.type, Number)) for a in parser._actions
            if a.option_strings and a.nargs != 0 and not a.choices and a.dest not in ("help", "output")]


@pytest.mark.slow
@pytest.mark.parametrize("path", list(BASES), ids=" ".join)
def test_every_option_at_bad_values(path, tmp_path, capsys):
    chart, depth = tmp_path / "chart.exr", tmp_path / "depth.npy"
    write_image(chart, np.full((48, 64), 0.5, np.float32), provenance=make_provenance(command="test", arcmin_per_px=1.0))
    np.save(depth, np.full((48, 64), 2.0))
    fit_image, fit_reference = tmp_path / "fit_image.exr", tmp_path / "fit_reference.exr"
    if path == ("fit-rx",):  # a +1.50 DS capture of a letter and its sharp reference (tests/fit/synthetic.py)
        from tests.fit.synthetic import capture
        from vissim.optics.rx.trial_lens import TrialLens

        blurred, sharp, _ = capture(TrialLens(1.5))
        for file, pixels in ((fit_image, blurred), (fit_reference, sharp)):
            write_image(file, pixels.astype(np.float32), provenance=make_provenance(command="test", arcmin_per_px=1.0))
    out = tmp_path / "out"

    def invoke(argv):
        shutil.rmtree(out, ignore_errors=True)
        out.mkdir()
        argv = [a.format(out=out, chart=chart, depth=depth, fit_image=fit_image, fit_reference=fit_reference)
                for a in argv]
        code = main(argv)
        _, err = capsys.readouterr()
        lines = [line for line in err.splitlines() if line.strip() and ": warning: " not in line]
        return code, lines

    code, lines = invoke(BASES[path])
    assert code == 0, lines
    failures = []
    for option, numeric in _options(path):
        for value in VALUES:
            argv = list(BASES[path])
            if option in argv:
                argv[argv.index(option) + 1] = value
            else:
                argv += [option, value]
            code, lines = invoke(argv)
            clean = code == 0 or (code == 2 and len(lines) == 1 and lines[0].startswith("vissim: error: ")
                                  and not [p for p in out.rglob("*") if p.is_file()])  # an error writes nothing
            if numeric and value == "nan" and code != 2:  # a numeric option never takes NaN
                clean = False
            if not clean:
                failures.append(f"{option} {value!r}: exit {code}: {' / '.join(lines)[:200]}")
    assert not failures, "\n".join(failures)
