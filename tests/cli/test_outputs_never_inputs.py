"""No command writes over one of its inputs, however the output path spells it, with or without --overwrite.

Property: for every command that reads files and writes files, an output spelled as one of its
inputs (the same path, ``dir/../dir/x``, a relative path, a symlink, a hard link, a path through
a symlinked folder; for folder outputs also the input's folder and the one above) exits 2 with
one ``vissim: error:`` line naming the rule, and every file under the test folder keeps its bytes.
Oracle: the bytes on disk before and after (vissim.atomic.check_outputs_apart decides the rule).
"""

import itertools
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from vissim.cli import build_parser, main
from vissim.imageio import write_image

REPO = Path(__file__).resolve().parents[2]
SPELLINGS = ("same", "dotdot", "relative", "symlink", "hardlink", "through-symlinked-folder")
_names = itertools.count()


def _image(path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    pixels = np.linspace(0.1, 0.9, 256, dtype=np.float32).reshape(16, 16)
    return write_image(path, pixels, arcmin_per_px=1.0)


def _copy(source: str, path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(REPO / source, path)
    return path


# Each case: (inputs a clash may target, argv given the spelled target and which input it clashes with).
def blur(root):
    chart = _image(root / "in" / "chart.png")
    return [chart], lambda out, _: ["blur", str(chart), "-o", out, "--rx", "-1.00 DS", "--pupil-mm", "3"]


def blur_depth(root):
    image = _image(root / "in" / "aif.exr")
    depth = root / "in" / "depth.npy"
    np.save(depth, np.full((16, 16), 2.0, np.float32))
    return [image, depth], lambda out, _: ["blur-depth", str(image), str(depth), "-o", out, "--rx", "-1.00 DS",
                                           "--pupil-mm", "3"]


def fit_rx(root):
    image, reference = _image(root / "in" / "capture.png"), _image(root / "in" / "reference.exr")
    return [image, reference], lambda out, _: ["fit-rx", str(image), "--reference", str(reference), "--pupil-mm",
                                               "3", "-o", out]


def render_bench(root):
    scene = _copy("scenes/dslr_bench.toml", root / "in" / "bench.toml")
    return [scene], lambda out, _: ["render", "bench", "--scene", str(scene), "-o", out]


def render_atv(root):
    scene = _copy("scenes/atv_tube.toml", root / "in" / "atv.toml")
    return [scene], lambda out, _: ["render", "atv", "--scene", str(scene), "-o", out]


def render_eye(root):
    scene = _copy("scenes/eye.toml", root / "in" / "eye.toml")
    return [scene], lambda out, _: ["render", "eye", "--scene", str(scene), "-o", out]


def render_depth(root):
    scene = _copy("scenes/depth_panels.toml", root / "in" / "panels.toml")
    others = {"-o": str(root / "o.exr"), "--all-in-focus": str(root / "aif.exr"), "--depth": str(root / "d.exr")}

    def argv(out, option):
        return ["render", "depth", str(scene), *itertools.chain(*{**others, option: out}.items())]

    return [(scene, option) for option in others], argv


def validate(root):
    campaign = root / "in" / "campaign.toml"
    campaign.parent.mkdir(parents=True)
    campaign.write_text('[campaign]\nname = "tiny"\nspp = 4\ntile_px = [48, 48]\n'
                        '[[item]]\nletter = "K"\nlogmar = 0.5\n')
    return [campaign, campaign.parent, root], lambda out, _: ["validate", str(campaign), "-o", out]


def atv_analyze(root):
    data = _copy("validation/atv/subject_001.json", root / "data" / "subject_001.json").parent
    return [data, root], lambda out, _: ["atv", "analyze", str(data), "-o", out]


CASES = {"blur": blur, "blur-depth": blur_depth, "fit-rx": fit_rx, "render bench": render_bench,
         "render atv": render_atv, "render depth": render_depth, "render eye": render_eye, "validate": validate, "atv analyze": atv_analyze}
#: Commands with an output but no input file (nothing to clash with); the outputs of chart/psf are
#: checked against each other by the output transaction (tests/cli/test_output_safety.py).
NO_INPUT_FILES = {"psf", "chart", "demo", "atv simulate", "atv run", "population"}
HAS_OVERWRITE = {"blur", "blur-depth", "fit-rx", "render bench", "render atv", "render depth", "atv analyze",
                 "render eye"}


def spelled(target: Path, how: str, root: Path) -> str:
    n = next(_names)
    if how == "same":
        return str(target)
    if how == "dotdot":
        return str(target.parent / ".." / target.parent.name / target.name)
    if how == "relative":
        return os.path.join(".", os.path.relpath(target))
    if how == "through-symlinked-folder":
        alias = root / f"alias{n}"
        alias.symlink_to(target.parent, target_is_directory=True)
        return str(alias / target.name)
    link = root / "links" / f"link{n}{target.suffix}"
    link.parent.mkdir(exist_ok=True)
    if how == "hardlink" and target.is_file():
        os.link(target, link)
    else:  # a symlink (a folder cannot be hard-linked)
        link.symlink_to(target, target_is_directory=target.is_dir())
    return str(link)


def snapshot(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


def leaf_commands(parser, prefix=()):
    """(command words, parser) of every runnable sub-command."""
    for action in parser._actions:
        if action.__class__.__name__ == "_SubParsersAction":
            for name, sub in action.choices.items():
                yield from leaf_commands(sub, (*prefix, name))
            return
    yield " ".join(prefix), parser


def test_every_command_with_an_output_is_classified():
    """A new command that writes files must join CASES (it reads files) or NO_INPUT_FILES."""
    writers = {name for name, parser in leaf_commands(build_parser())
               if any("--output" in action.option_strings for action in parser._actions)}
    assert writers == set(CASES) | NO_INPUT_FILES


@settings(max_examples=80, deadline=None)
@given(command=st.sampled_from(sorted(CASES)), how=st.sampled_from(SPELLINGS), overwrite=st.booleans(),
       pick=st.integers(0, 5))
def test_no_command_writes_over_its_input(command, how, overwrite, pick):
    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder).resolve()
        targets, argv = CASES[command](root)
        target = targets[pick % len(targets)]
        target, option = target if isinstance(target, tuple) else (target, None)
        words = argv(spelled(target, how, root), option)
        words += ["--overwrite"] if overwrite and command in HAS_OVERWRITE else []
        before = snapshot(root)
        with CapturedStderr() as err:
            code = main(words)
        lines = err.text().strip().splitlines()
        assert code == 2 and len(lines) == 1, (words, lines)
        assert lines[0].startswith("vissim: error: ") and "an output never replaces an input" in lines[0], lines
        assert snapshot(root) == before


class CapturedStderr:
    """stderr of an in-process command (hypothesis runs many examples in one test: no capsys)."""

    def __enter__(self):
        import contextlib
        import io

        self._buffer = io.StringIO()
        self._redirect = contextlib.redirect_stderr(self._buffer)
        self._redirect.__enter__()
        return self

    def __exit__(self, *exc):
        return self._redirect.__exit__(*exc)

    def text(self) -> str:
        return self._buffer.getvalue()
