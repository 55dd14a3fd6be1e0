#!/usr/bin/env bash
# Regenerate constraints.txt: the newest versions pyproject.toml allows, resolved in a scratch venv.
#
# Then run the suite on them (`bash scripts/setup.sh && .venv/bin/python -m pytest`, plus
# `-m slow`) and commit constraints.txt only if it passes.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-$(command -v python3.11 || command -v python3)}"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
"$PYTHON" -m venv "$scratch/venv"
"$scratch/venv/bin/python" -m pip install --quiet --disable-pip-version-check ".[test,bench,peers,docs]"
{
    echo "# The stack the test suite passes on, installed by scripts/setup.sh (pip -c)."
    echo "# Made by scripts/lock.sh on $(date -u +%Y-%m-%d) with $("$PYTHON" --version 2>&1) on $(uname -m)."
    echo "# To upgrade: bash scripts/lock.sh, then rerun the suite; commit this file if it passes."
    "$scratch/venv/bin/python" -m pip freeze --exclude vissim --exclude pip --exclude setuptools --exclude wheel
} > constraints.txt.tmp
mv constraints.txt.tmp constraints.txt
echo "lock: wrote constraints.txt ($(grep -vc '^#' constraints.txt) packages); now rerun the suite"
