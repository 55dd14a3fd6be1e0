#!/usr/bin/env bash
# Install vissim and everything it needs into ./.venv (safe to run again).
#
# * Python >= 3.11 (python3.11 if present, else python3).
# * LLVM 19 for Mitsuba's fast CPU variants (llvm_*): Debian's libllvm19 when this user may
#   install packages. Without it vissim still works, on Mitsuba's scalar_* variants.
# * Python packages at the versions pinned in constraints.txt.
set -euo pipefail
cd "$(dirname "$0")/.."

have_llvm19() { ls /lib/*-linux-gnu/libLLVM.so.19* /usr/lib/*-linux-gnu/libLLVM.so.19* >/dev/null 2>&1; }
if ! have_llvm19 && command -v apt-get >/dev/null 2>&1; then
    if [ "$(id -u)" = 0 ]; then SUDO=""; elif sudo -n true 2>/dev/null; then SUDO="sudo -n"; else SUDO="none"; fi
    if [ "$SUDO" != "none" ]; then
        echo "setup: installing libllvm19 (for Mitsuba's llvm_* variants)"
        $SUDO apt-get install -y -qq libllvm19 >/dev/null 2>&1 \
            || { $SUDO apt-get update -qq >/dev/null 2>&1 && $SUDO apt-get install -y -qq libllvm19 >/dev/null 2>&1; } \
            || echo "setup: could not install libllvm19; Mitsuba will run on its slower scalar_* variants"
    else
        echo "setup: no permission to install libllvm19; Mitsuba will run on its slower scalar_* variants"
    fi
fi

PYTHON="${PYTHON:-$(command -v python3.11 || command -v python3)}"
"$PYTHON" -c 'import sys; sys.exit(sys.version_info < (3, 11))' \
    || { echo "setup: vissim needs Python >= 3.11; $PYTHON is $("$PYTHON" --version 2>&1)" >&2; exit 1; }
[ -x .venv/bin/python ] || "$PYTHON" -m venv .venv
# The exact stack the suite passes on (constraints.txt; scripts/lock.sh regenerates it).
.venv/bin/python -m pip install --quiet --disable-pip-version-check -c constraints.txt -e ".[test]"
echo "setup: vissim installed in .venv ($(.venv/bin/vissim --version))"
