#!/usr/bin/env bash
# Check that pyproject.toml's lower bounds are honest: install each dependency at its lower
# bound (">=X" read as "==X") in a scratch venv and run the default test suite there.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-$(command -v python3.11 || command -v python3)}"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
"$PYTHON" - > "$scratch/floor.txt" <<'PY'
import re, tomllib
project = tomllib.load(open("pyproject.toml", "rb"))["project"]
for spec in project["dependencies"] + project["optional-dependencies"]["test"]:
    name, low = re.match(r"([A-Za-z0-9_.-]+)(?:\[[^\]]*\])?>=([0-9][^,;\s]*)", spec).groups()
    print(f"{name}=={low}")
PY
echo "floor: $(tr '\n' ' ' < "$scratch/floor.txt")"
"$PYTHON" -m venv "$scratch/venv"
"$scratch/venv/bin/python" -m pip install --quiet --disable-pip-version-check -c "$scratch/floor.txt" ".[test]"
"$scratch/venv/bin/python" -m pytest -q -p no:cacheprovider
