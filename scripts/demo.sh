#!/usr/bin/env bash
# The one-command demo. On a machine with Python 3.9+ (3.11 tested) it creates
# .venv here, installs PrintWatch with OctoPrint into it (once; again only when
# pyproject.toml changes), then runs `printwatch demo` with your arguments:
#
#   scripts/demo.sh                          # twisted vase, 6 cameras, runout part-way
#   scripts/demo.sh --part gear --failure spaghetti
#   scripts/demo.sh --failure none --cameras 2
#   scripts/demo.sh --headless               # no browser: summary, exit 1 on a wrong outcome
#   scripts/demo.sh --help                   # every option
#
# Needs only Python and pip's package index (no system packages; no browser on the
# machine for --headless). Set PYTHON=/path/to/python3.11 to pick the interpreter.
set -euo pipefail
cd "$(dirname "$0")/.."

pick_python() {
    if [ -n "${PYTHON:-}" ]; then echo "$PYTHON"; return; fi
    for candidate in python3.11 python3.12 python3.13 python3.10 python3; do
        if command -v "$candidate" >/dev/null 2>&1; then echo "$candidate"; return; fi
    done
    echo "error: no python3 found; install Python 3.11 (Debian: sudo apt-get install python3 python3-venv)" >&2
    exit 1
}

if [ ! -x .venv/bin/python ]; then
    PY=$(pick_python)
    if ! "$PY" -c 'import sys; sys.exit(sys.version_info < (3, 9))'; then
        echo "error: $PY is Python $("$PY" -c 'import platform; print(platform.python_version())'); PrintWatch needs 3.9 or newer (3.11 tested)" >&2
        exit 1
    fi
    echo "Creating .venv with $PY ..."
    if ! "$PY" -m venv .venv; then
        echo "error: could not create a virtual environment; on Debian/Ubuntu: sudo apt-get install python3-venv" >&2
        exit 1
    fi
fi

# Install (or update) only when the dependencies changed since the last install.
stamp=.venv/.printwatch-demo-installed
wanted=$(.venv/bin/python -c 'import hashlib; print(hashlib.sha256(open("pyproject.toml", "rb").read()).hexdigest())')
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$wanted" ] || ! .venv/bin/python -c 'import octoprint, octoprint_printwatch' 2>/dev/null; then
    echo "Installing PrintWatch and OctoPrint into .venv (a few minutes the first time) ..."
    .venv/bin/python -m pip install -q --upgrade pip
    .venv/bin/python -m pip install -q -e ".[octoprint]"
    echo "$wanted" > "$stamp"
fi

exec .venv/bin/printwatch demo "$@"
