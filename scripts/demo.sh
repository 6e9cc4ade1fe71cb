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
if [[ " ${targets[*]} " == *" dynahand_python "* ]]; then
  # `import dynahand` for Debian's /usr/bin/python3: the module's install component (the module,
  # its stub and dynahand_batch.py) into lib/python3.X/dist-packages under the install prefix
  # (/usr/local: on that Python's sys.path), when this user may write there.
  cache() { sed -n "s/^$1:[A-Z]*=//p" build/release/CMakeCache.txt; }
  python=$(cache Python3_EXECUTABLE)
  dir=$(cache DYNAHAND_PYTHON_INSTALL_DIR)
  [[ $dir == /* ]] || dir="$(cache CMAKE_INSTALL_PREFIX)/$dir"
  existing=$dir
  while [[ ! -e $existing ]]; do existing=$(dirname "$existing"); done
  if [[ $(id -u) == 0 || -w $existing ]] &&
    cmake --install build/release --component python >/dev/null; then
    if (cd / && "$python" -c "import dynahand" 2>/dev/null); then
      echo "Python module: installed into $dir ($python -c \"import dynahand\" works)"
    else
      echo "Python module: installed into $dir, which $python does not search" \
        "(add it to PYTHONPATH)"
    fi
  else
    echo "Python module: build/release/python; for $python to find it: sudo cmake --install" \
      "build/release --component python (into $dir), or PYTHONPATH=build/release/python"
  fi
fi
exec build/release/apps/dynahand demo --out out "$@"
