"""Write the CLI reference (Markdown) from vissim's argparse parser: ``python scripts/cli_reference.py OUT.md``."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path


def _subcommands(parser: argparse.ArgumentParser):
    for action in parser._actions:  # argparse keeps sub-parsers only here
        if isinstance(action, argparse._SubParsersAction):
            yield from action.choices.items()


def _sections(parser: argparse.ArgumentParser, prog: str, depth: int):
    yield f"{'#' * depth} `{prog}`\n\n```text\n{parser.format_help().rstrip()}\n```\n"
    for name, sub in _subcommands(parser):
        yield from _sections(sub, f"{prog} {name}", min(depth + 1, 4))


def cli_reference() -> str:
    os.environ["COLUMNS"] = "100"  # argparse wraps help text to the terminal: fix it
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's vissim
    from vissim.cli import build_parser

    parser = build_parser()
    head = ("# CLI reference\n\nGenerated from the command line's own parser by "
            "`scripts/cli_reference.py` (run by `scripts/docs.sh`); `vissim COMMAND --help` "
            "prints the same text.\n")
    return "\n".join([head, *_sections(parser, "vissim", 2)])


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/cli.md")
    out.write_text(cli_reference())
    print(f"cli_reference: wrote {out}")
