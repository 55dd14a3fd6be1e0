"""Instant start: ``vissim --help``, ``vissim eye --help`` and most commands' help import no numerical code.

Measured, not timed: a fresh interpreter runs the command and lists the heavy packages in ``sys.modules``
(a timing would depend on the machine and its load).  A command imports what it uses when it runs.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from vissim.cli import COMMANDS, build_parser

HEAVY = ("numpy", "scipy", "OpenEXR", "mitsuba", "drjit", "matplotlib", "skimage", "dask", "distributed", "PIL",
         "rawpy", "imageio")

PROBE = """
import json, sys
from vissim.cli import main
main({argv!r})
print(json.dumps(sorted({{m.split('.')[0] for m in sys.modules}} & set({heavy!r}))))
"""


#: The commands whose help is light so far (the image and render commands' help still loads numpy).
LIGHT_COMMANDS = ("rx", "trial-lens", "eye", "population", "fit-rx", "validate", "report", "atv", "bench")


@pytest.mark.parametrize("argv", [["--help"], ["bogus"], *([c, "--help"] for c in LIGHT_COMMANDS)])
def test_help_and_a_refusal_import_no_numerical_code(argv):
    done = subprocess.run([sys.executable, "-c", PROBE.format(argv=argv, heavy=HEAVY)], capture_output=True,
                          text=True, check=True)
    assert json.loads(done.stdout.strip().splitlines()[-1]) == []


def test_each_command_listed_is_the_one_its_module_builds():
    """The light list (`COMMANDS`) and the commands' own parsers agree: names, order and lines."""
    full = next(a for a in build_parser()._actions if a.__class__.__name__ == "_SubParsersAction")
    assert [(a.dest, a.help) for a in full._choices_actions] == [(n, line) for n, (_, line) in COMMANDS.items()]
    for name in COMMANDS:
        one = next(a for a in build_parser(name)._actions if a.__class__.__name__ == "_SubParsersAction")
        assert list(one.choices) == list(COMMANDS) and one.choices[name].get_default("func") is not None


def test_the_light_names_are_the_packages_own():
    """The dataset names the help texts read without loading numpy are the package's data files, each loadable."""
    from vissim.optics.eyes.defaults import MEASURED_DATASET_NAMES
    from vissim.optics.eyes.measured.datasets import DATA_DIR, load_dataset

    assert sorted(MEASURED_DATASET_NAMES) == sorted(p.stem for p in DATA_DIR.glob("*.npz"))
    assert all(load_dataset(name).name == name for name in MEASURED_DATASET_NAMES)
