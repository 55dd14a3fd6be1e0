"""The ``vissim`` command line: thin wrappers that parse, call one library function and print.

Each sub-command lives in its own module exposing ``add_parser(subparsers)``; the module
registers its parser and sets ``func`` (a callable taking the parsed namespace and returning
an exit code) with ``parser.set_defaults(func=...)``.  Bad input raises
`vissim.errors.VissimInputError`; `main` prints its one line and exits 2.

A command's files appear together when it succeeds, or not at all
(`vissim.atomic.output_transaction`); a command that resumes from what it already wrote
(``validate``, ``report``) sets ``writes_progressively=True`` and writes file by file.
A transactional command's ``wrote ...`` lines are printed once its files are in place,
unless it sets ``prints_live=True``: a person reads its lines as they come
(``atv run --observer person``), and its files still appear together.
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import importlib
import io
import logging
import re
import sys

from vissim import __version__
from vissim.atomic import output_transaction
from vissim.cli._parser import VissimArgumentParser
from vissim.errors import VissimError

#: The sub-commands, in the order ``vissim --help`` lists them: name -> (the module that builds its parser, its
#: line in that list). Only the command being run has its module imported (`build_parser`).
COMMANDS = {
    "rx": ("vissim.cli.rx",
              "parse a prescription: sphere/cylinder/axis, power vector, Zernike coefficients"),
    "trial-lens": ("vissim.cli.trial_lens",
              "power and magnification a trial lens adds at the camera"),
    "eye": ("vissim.cli.eye",
              "trace a schematic eye: power, pupils, Zernikes, refraction, MTF"),
    "population": ("vissim.cli.population",
              "measured eyes en masse: MTF, Strehl, refraction per eye, their quantiles, beside published MTFs"),
    "fit-rx": ("vissim.cli.fit_rx",
              "fit the refraction a capture shows (sphere, cylinder, axis added at the camera)"),
    "psf": ("vissim.cli.psf",
              "compute a point-spread function"),
    "chart": ("vissim.cli.chart",
              "render a LogMAR letter chart, a single letter or a thesis tile"),
    "blur": ("vissim.cli.blur",
              "blur an image through a prescription or Zernike wavefront"),
    "blur-depth": ("vissim.cli.blur_depth",
              "blur an RGB-D image: defocus per depth for an uncorrected eye, with occlusion"),
    "demo": ("vissim.cli.demo",
              "write a LogMAR chart, two PSFs and the blurred charts (built-in default)"),
    "render": ("vissim.cli.render",
              "render the virtual optical bench (Mitsuba 3) to a linear EXR"),
    "validate": ("vissim.cli.validate",
              "run a validation campaign: bench renders vs Fourier simulations"),
    "report": ("vissim.cli.validate",
              "rebuild a campaign run's report from its results"),
    "atv": ("vissim.cli.atv",
              "absolute threshold for vision: analyse, simulate, measure"),
    "bench": ("vissim.cli.bench",
              "the virtual DSLR bench's own optics (traced wavefront)"),
}


def command_help(name: str) -> str:
    """The line ``vissim --help`` gives the command ``name``."""
    return COMMANDS[name][1]


def build_parser(command: str | None = "*") -> argparse.ArgumentParser:
    """The ``vissim`` parser. Every command's options with ``command="*"``; with a command's name, that
    command's (and its module's other commands') options only, the rest listed by name and line, their modules
    (and what they import) left unloaded; with None, every command listed only (``vissim --help``)."""
    parser = VissimArgumentParser(prog="vissim",
                                  description="Simulate how refractive errors blur what an eye or a camera sees.")
    parser.add_argument("--version", action="version", version=f"vissim {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="log more (-vv for debug)")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    wanted = None if command in (None, "*") else COMMANDS[command][0]
    built = set()
    for name, (module, line) in COMMANDS.items():
        if command == "*" or module == wanted:
            if module not in built:
                importlib.import_module(module).add_parser(subparsers)
                built.add(module)
        else:
            subparsers.add_parser(name, help=line)
    return parser


def _command_named(argv: list[str]) -> str | None:
    """The command ``argv`` runs (its first word that names one), or None."""
    return next((token for token in argv if token in COMMANDS), None)


_NEGATIVE_VALUE = re.compile(r"^-(?:\d|\.\d)")


def _protect_negative_values(argv: list[str]) -> list[str]:
    """Let '-2.00/-1.25x180' be a value: argparse would take it for an option.

    No vissim option starts with a digit, so a leading space marks such tokens as values while
    argparse reads them; `_unprotect` takes it off again.
    """
    return [" " + a if _NEGATIVE_VALUE.match(a) else a for a in argv]


def _unprotect(args: argparse.Namespace) -> argparse.Namespace:
    """Strip the leading space `_protect_negative_values` added to string values."""

    def strip(value):
        if isinstance(value, str) and value.startswith(" ") and _NEGATIVE_VALUE.match(value[1:]):
            return value[1:]
        if isinstance(value, list):
            return [strip(v) for v in value]
        return value

    for key, value in vars(args).items():
        setattr(args, key, strip(value))
    return args


class _LogLineFormatter(logging.Formatter):
    """Log records as the command line's other lines: 'vissim: warning: ...', like 'vissim: error: ...'."""

    def format(self, record: logging.LogRecord) -> str:
        return f"vissim: {record.levelname.lower()}: {super().format(record)}"


def _run_command(args: argparse.Namespace) -> int:
    """Run the command; a transactional one's stdout ('wrote ...') is shown only once its files are in place."""
    if getattr(args, "writes_progressively", False):
        return int(args.func(args) or 0)
    if getattr(args, "prints_live", False):
        with output_transaction():
            return int(args.func(args) or 0)
    said = io.StringIO()
    with output_transaction(), contextlib.redirect_stdout(said):
        code = int(args.func(args) or 0)
    sys.stdout.write(said.getvalue())
    return code


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(_command_named(argv))
    try:
        args = _unprotect(parser.parse_args(_protect_negative_values(argv)))
    except SystemExit as exc:  # --help, --version, or one 'vissim: error:' line already printed
        return exc.code if isinstance(exc.code, int) else 2
    handler = logging.StreamHandler()
    handler.setFormatter(_LogLineFormatter("%(message)s"))
    logging.basicConfig(level=logging.WARNING - 10 * min(args.verbose, 2), handlers=[handler])
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return _run_command(args)
    except VissimError as exc:
        print(f"vissim: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("vissim: interrupted; no partial output was left behind", file=sys.stderr)
        return 130


def run() -> None:
    """The ``vissim`` command: `main`, then exit with its code.

    The process ends here, so what it made is frozen first (`gc.freeze`): the interpreter's last garbage
    collection skips it (0.2 s after a campaign) and the system takes the memory back with the process.
    """
    code = main()
    gc.freeze()
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    run()
