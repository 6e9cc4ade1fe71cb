#!/usr/bin/env bash
# Fuzzes the sensor readers (PNG depth, NYU PNG, camera.json, NAME.json + NAME.rs,
# groundtruth.jsonl) with libFuzzer + ASan + UBSan for a bounded time. Not part of
# the default build or CI test run.
# Usage: scripts/fuzz.sh [SECONDS]   (default 600)
# Installs clang if missing. Builds in build/fuzz; the corpus grows in
# build/fuzz/corpus, crashes land in build/fuzz/artifacts. Exits non-zero on a crash.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-600}
if [[ ! $seconds =~ ^[0-9]+$ ]] || (( seconds < 1 )); then
  echo "fuzz.sh: SECONDS must be a positive whole number, got '$seconds'" >&2
  exit 2
fi

bash scripts/install-deps.sh
if ! command -v clang++ >/dev/null 2>&1; then
  echo "fuzz.sh: installing clang"
  sudo_cmd=()
  [[ $(id -u) -ne 0 ]] && sudo_cmd=(sudo)
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends clang >/dev/null
fi

build=build/fuzz
CC=clang CXX=clang++ cmake -S fuzz -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$build" --target fuzz_sensor_readers make_sensor_seeds -j "$(nproc)"

mkdir -p "$build/corpus" "$build/artifacts"
"$build/make_sensor_seeds" "$build/seeds"
echo "fuzz.sh: fuzzing for $seconds s (corpus $build/corpus, crashes in $build/artifacts)"
# -rss_limit_mb: a reader asking for huge buffers is a bug too.
if "$build/fuzz_sensor_readers" "$build/corpus" "$build/seeds" \
     -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
     -artifact_prefix="$build/artifacts/" -print_final_stats=1; then
  echo "fuzz.sh: finished, no crash found in $seconds s"
else
  status=$?
  echo "fuzz.sh: the fuzzer stopped with status $status; reproducer(s) in $build/artifacts:" >&2
  ls -1 "$build/artifacts" >&2
  exit "$status"
fi
