#!/usr/bin/env bash
# Installs the Debian 12 packages dynahand needs to build, test and run, and only
# those that are missing. Idempotent; quiet when everything is already there.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkgconf ccache
  libeigen3-dev libqhull-dev libccd-dev
  libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-videoio-dev
  libopencv-dnn-dev               # the learned detector's inference (ONNX through OpenCV DNN)
  python3-numpy python3-torch python3-onnx  # the detector's training script (train/), Debian's /usr/bin/python3
  pybind11-dev python3-dev python3-pytest   # `import dynahand` (python/) and its tests
  python3-dask python3-distributed          # `dynahand batch` (python/dynahand_batch.py): Dask tasks
  nlohmann-json3-dev libcli11-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang-format                    # scripts/test.sh checks the sources' formatting
  doxygen                         # the API reference of include/dynahand (api_docs_doxygen test)
  libopenni2-dev libfreenect-dev
  libwebsocketpp-dev libasio-dev  # dynahand serve: WebSocket + HTTP server
  chromium                        # the viewer's browser test (driven by playwright-core)
)

if ! command -v dpkg-query >/dev/null 2>&1 || ! command -v apt-get >/dev/null 2>&1; then
  echo "install-deps: apt-get/dpkg not found; dynahand's installer supports Debian 12 (bookworm)." >&2
  echo "install-deps: install these packages by other means: ${packages[*]}" >&2
  exit 1
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
# The viewer page's JavaScript packages (three.js, esbuild, playwright-core), pinned by
# web/package-lock.json, installed into web/node_modules when missing.
install_web_packages() {
  local web
  web="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/web"
  [[ -d "$web/node_modules/three" && -d "$web/node_modules/playwright-core" ]] && return 0
  if ! command -v npm >/dev/null 2>&1; then
    echo "install-deps: npm not found; the viewer page and its browser test will be skipped." >&2
    return 0
  fi
  echo "install-deps: npm ci in web/"
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error)
}

if [[ ${#missing[@]} -eq 0 ]]; then
  install_web_packages
  exit 0
fi

sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null 2>&1; then sudo_cmd=(sudo); else
    echo "install-deps: missing packages (${missing[*]}) and not root; run as root or install sudo." >&2
    exit 1
  fi
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
log=$(mktemp)
if ! { "${sudo_cmd[@]}" apt-get update -qq && \
       "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"; } >"$log" 2>&1; then
  echo "install-deps: apt-get failed; its output:" >&2
  cat "$log" >&2
  rm -f "$log"
  exit 1
fi
rm -f "$log"
install_web_packages
