"""Instant start: ``vissim --help`` and every command's help import no numerical code; ``vissim eye --json`` no
scipy; and no vissim module imports one of scipy's namespaces when it is imported.

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


@pytest.mark.parametrize("argv", [["--help"], ["bogus"], *([c, "--help"] for c in COMMANDS)])
def test_help_and_a_refusal_import_no_numerical_code(argv):
    done = subprocess.run([sys.executable, "-c", PROBE.format(argv=argv, heavy=HEAVY)], capture_output=True,
                          text=True, check=True)
    assert json.loads(done.stdout.strip().splitlines()[-1]) == []


def test_an_eye_report_imports_no_scipy():
    """The eye's refraction and aberrations (``vissim eye --json``, no MTF) need the trace and NumPy only: scipy's
    import alone (its FFT module pulls in its special functions) took longer than the whole report."""
    argv = ["eye", "--eye-model", "navarro-1985", "--pupil-mm", "4", "--json"]
    probe = PROBE.replace("main({argv!r})", "import contextlib, io\nwith contextlib.redirect_stdout(io.StringIO()):\n"
                                              "    main({argv!r})")
    done = subprocess.run([sys.executable, "-c", probe.format(argv=argv, heavy=HEAVY)], capture_output=True,
                          text=True, check=True)
    assert json.loads(done.stdout.strip().splitlines()[-1]) == ["numpy"]


SCIPY_NAMESPACES = ("scipy.fft", "scipy.special", "scipy.ndimage", "scipy.signal", "scipy.stats", "scipy.optimize",
                    "scipy.sparse", "scipy.linalg", "scipy.integrate", "scipy.interpolate")


def test_no_module_imports_scipy_when_imported():
    """Every vissim module (its ``__main__`` aside: it runs the command line) imported in one fresh interpreter leaves
    scipy's namespaces unloaded: each is reached through `vissim.lazy_import.lazy_module` when first used."""
    probe = """
import importlib, json, pkgutil, sys
import vissim
names = [m.name for m in pkgutil.walk_packages(vissim.__path__, "vissim.") if m.name != "vissim.__main__"]
for name in names:
    importlib.import_module(name)
print(json.dumps(sorted(m for m in sys.modules if m.startswith({namespaces!r}))))
"""
    done = subprocess.run([sys.executable, "-c", probe.format(namespaces=SCIPY_NAMESPACES)], capture_output=True,
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


@pytest.mark.parametrize("argv, code", [(["--version"], 0), (["rx", "-2.00"], 0), (["rx", "bogus"], 2)])
def test_the_command_exits_with_mains_code(argv, code):
    """``python -m vissim`` (as the ``vissim`` script) runs `main` and exits with its code: 0, or 2 after one error
    line; the process's objects are frozen for its exit, never those of a caller of `main`."""
    done = subprocess.run([sys.executable, "-m", "vissim", *argv], capture_output=True, text=True, timeout=120)
    assert done.returncode == code, done.stderr
    assert done.stderr.count("vissim: error:") == (1 if code == 2 else 0)
    import gc

    from vissim.cli import main

    frozen = gc.get_freeze_count()
    assert main(["--version"]) == 0 and gc.get_freeze_count() == frozen
