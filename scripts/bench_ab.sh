#!/usr/bin/env bash
# Compares the tracker's speed between builds on a noisy shared machine: runs the given
# bench_tracker binaries in rotation, ROUNDS times each, and prints per binary the least,
# median and largest p50 per-frame time (ms) of one benchmark. Rotation spreads outside load
# over all of them; a single run says little about a change of a few per cent.
# Usage: scripts/bench_ab.sh ROUNDS BENCH_TRACKER [BENCH_TRACKER ...]
#   Each BENCH_TRACKER is a command line, so one binary can run with a tracker setting changed:
#   'DYNAHAND_BENCH_SET=detector.engageDistanceM=0.02 build/release/bench/track/bench_tracker'
#   FILTER: the benchmark (default wave_tof_320x240/, e.g. count_tof_320x240/, wave_sl_640x480/)
set -euo pipefail
if [[ $# -lt 2 ]]; then
  sed -n '2,10p' "$0"
  exit 2
fi
rounds=$1
shift
filter=${FILTER:-wave_tof_320x240/}
declare -A times
for ((round = 0; round < rounds; ++round)); do
  for bin in "$@"; do
    p50=$(bash -c "$bin --benchmark_filter='$filter'" 2>&1 | sed -n 's/.*p50_ms=\([0-9.]*\).*/\1/p' | head -1)
    times[$bin]="${times[$bin]:-} ${p50:-nan}"
  done
done
for bin in "$@"; do
  echo "${times[$bin]}" | tr ' ' '\n' | sed '/^$/d' | sort -g |
    awk -v name="$bin" '{v[NR] = $1} END {
      printf "%s: n=%d least %.3f median %.3f largest %.3f ms\n", name, NR, v[1], v[int((NR + 1) / 2)], v[NR]}'
done
