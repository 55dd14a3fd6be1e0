#!/usr/bin/env bash
# Build the documentation site into ./site (open site/index.html). Run scripts/setup.sh first.
#
# * Installs the docs extra (mkdocs-material, mkdocstrings) into .venv at the versions pinned in
#   constraints.txt; scripts/setup.sh does not install it, so the test stack stays as it is.
# * Generates the CLI reference from vissim's argparse parser (docs/cli.md) and copies the
#   committed reports (validation/reports/, validation/atv/report/) into docs/reports/; both are build products.
# * mkdocs build --strict: a warning (a broken link or reference, a missing docstring target)
#   fails the build.
# * scripts/check_docs.py fails it too, before mkdocs on the sources (a Sphinx role, a documented
#   default that differs from the signature's, a pip extra pyproject.toml lacks) and after it on
#   the HTML (a raw role, a shown default against inspect.signature, a link or file not on the site).
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x .venv/bin/python ] || { echo "docs: no .venv; run bash scripts/setup.sh first" >&2; exit 1; }
.venv/bin/python -m pip install --quiet --disable-pip-version-check -c constraints.txt -e ".[docs]"
.venv/bin/python scripts/cli_reference.py docs/cli.md
rm -rf docs/reports/thesis docs/reports/depth docs/reports/atv docs/reports/eye docs/reports/eye_measured docs/reports/population
for report in validation/reports/*/; do cp -r "$report" docs/reports/; done
cp -r validation/atv/report docs/reports/atv
.venv/bin/python scripts/check_docs.py --sources
NO_MKDOCS_2_WARNING=1 .venv/bin/python -m mkdocs build --strict --clean --site-dir site
.venv/bin/python scripts/check_docs.py --site site
echo "docs: site/index.html"
