#!/usr/bin/env bash
# README command 2: install what is missing, build, and run every test through CTest.
# Exits non-zero on any failure. Usage: scripts/test.sh [--preset NAME] [--no-asan]
#   default: the sources' formatting (clang-format, .clang-format), then the 'ci' preset
#   (Release, warnings as errors), then the 'ci-asan' preset (AddressSanitizer + UBSan)
#   over the same tests. `cmake --build --preset release --target format` fixes formatting.
set -euo pipefail
cd "$(dirname "$0")/.."

presets=(ci ci-asan)
while [[ $# -gt 0 ]]; do
  case "$1" in
    --preset) presets=("$2"); shift 2 ;;
    --no-asan) presets=(ci); shift ;;
    -h|--help) sed -n '2,6p' "$0"; exit 0 ;;
    *) echo "test.sh: unknown option $1" >&2; exit 2 ;;
  esac
done

bash scripts/install-deps.sh
jobs=$(nproc)
for preset in "${presets[@]}"; do
  echo "== dynahand tests: preset $preset =="
  cmake --preset "$preset" >/dev/null
  if [[ $preset == "${presets[0]}" ]]; then
    echo "== dynahand formatting (clang-format --dry-run --Werror) =="
    cmake --build --preset "$preset" --target format-check
  fi
  cmake --build --preset "$preset" -j "$jobs"
  ctest --preset "$preset" -j "$jobs"
done
