#!/usr/bin/env bash
# Installs everything dacph-drake needs into ./.venv: system tools (graphviz's dot,
# and Debian's chromium for the headless test of the HTML animation),
# the CPU build of torch (pinned here; the project itself only asks for a range),
# and the package with its test, Dask, Parquet, pandas, robots (example-robot-data)
# and docs (MkDocs) extras.
# Safe to run again.
set -euo pipefail
cd "$(dirname "$0")/.."
missing=()
command -v dot >/dev/null || missing+=(graphviz)
command -v chromium >/dev/null || missing+=(chromium)
if [ ${#missing[@]} -gt 0 ]; then
    SUDO=$([ "$(id -u)" = 0 ] && echo "" || echo sudo)
    $SUDO apt-get update -qq
    $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi
[ -x .venv/bin/python ] || python3 -m venv .venv
.venv/bin/pip install -q --upgrade pip
.venv/bin/pip install -q torch==2.13.0
.venv/bin/pip install -q -e ".[test,dask,parquet,pandas,robots,docs]"
# Compile the numba kernels of the closed loop once, into their on-disk cache.
.venv/bin/python -m dacph_drake.app.compile_kernels
