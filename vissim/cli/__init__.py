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
import importlib
import io
import logging
import re
import sys

from vissim import __version__
from vissim.atomic import output_transaction
from vissim.cli._parser import VissimArgumentParser
from vissim.errors import VissimError

#: Sub-command modules, in the order ``vissim --help`` lists them.
COMMAND_MODULES = (
    "vissim.cli.rx",
    "vissim.cli.trial_lens",
    "vissim.cli.eye",
    "vissim.cli.population",
    "vissim.cli.fit_rx",
    "vissim.cli.psf",
    "vissim.cli.chart",
    "vissim.cli.blur",
    "vissim.cli.blur_depth",
    "vissim.cli.demo",
    "vissim.cli.render",
    "vissim.cli.validate",
    "vissim.cli.atv",
    "vissim.cli.bench",
)


def build_parser() -> argparse.ArgumentParser:
    parser = VissimArgumentParser(prog="vissim",
                                  description="Simulate how refractive errors blur what an eye or a camera sees.")
    parser.add_argument("--version", action="version", version=f"vissim {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="log more (-vv for debug)")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).add_parser(subparsers)
    return parser


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
    parser = build_parser()
    try:
        args = _unprotect(parser.parse_args(_protect_negative_values(sys.argv[1:] if argv is None else list(argv))))
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


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
