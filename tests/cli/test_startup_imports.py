"""Instant start: ``vissim --help`` and ``vissim eye --help`` import no numerical code.

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


@pytest.mark.parametrize("argv", [["--help"], ["eye", "--help"], ["bogus"]])
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
