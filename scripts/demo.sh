#!/usr/bin/env bash
# README command 1: install what is missing, build Release and run the demo
# (synthesise a clip, track it, evaluate it, print the summary, write out/demo.png).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake --preset release >/dev/null
# Only the command and the Python module (not the tests and benchmarks): most of a cold
# build's time is elsewhere. The module is there when pybind11 and numpy were found.
targets=(dynahand_cli)
if cmake --build --preset release --target help | grep -q '^dynahand_python:'; then
  targets+=(dynahand_python)
fi
cmake --build --preset release -j "$(nproc)" --target "${targets[@]}"
exec build/release/apps/dynahand demo --out out "$@"
