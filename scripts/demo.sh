#!/usr/bin/env bash
# README command 1: install what is missing, build Release and run the demo
# (synthesise a clip, track it, evaluate it, print the summary, write out/demo.png).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release -j "$(nproc)"
exec build/release/apps/dynahand demo --out out "$@"
