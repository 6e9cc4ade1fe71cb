#!/usr/bin/env bash
# Whether a change keeps the tracker's results bit for bit: tracks five 100-frame synthetic
# clips (wave, count, finger-flips and fast-translation on tof; wrist-flex-roll on
# structured-light; ground-truth start) with the given dynahand binary and prints each clip's
# mean 21-keypoint error and a hash of its output without the timings, then one hash of all.
# Run it with the binaries before and after a change: equal ALL hashes, identical results.
# Usage: scripts/results_hash.sh [DYNAHAND_BINARY] [WORK_DIR]
#   defaults: build/release/apps/dynahand, /tmp/dynahand-results-hash (clips kept there)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "${1:-build/release/apps/dynahand}")
work=${2:-/tmp/dynahand-results-hash}
mkdir -p "$work"
clips=(wave:tof count:tof wrist-flex-roll:structured-light finger-flips:tof
       fast-translation:tof)
all=""
for entry in "${clips[@]}"; do
  motion=${entry%%:*}
  profile=${entry##*:}
  dir="$work/${motion}_${profile}"
  if [[ ! -f "$dir/synth.json" ]]; then
    rm -rf "$dir"
    "$bin" synth --motion "$motion" --profile "$profile" --frames 100 --out "$dir" >/dev/null 2>&1
  fi
  out="$work/${motion}_${profile}.jsonl"
  mean=$("$bin" track "$dir" --init gt --out "$out" 2>&1 |
         sed -n 's/.*21-keypoint.*mean \([0-9.]*\) mm.*/\1/p')
  hash=$(sed 's/"time_ms":[^,}]*//g' "$out" | md5sum | cut -c1-8)
  echo "${motion}_${profile} mean=${mean:-?} mm hash=$hash"
  all="$all$hash"
done
echo "ALL $(echo "$all" | md5sum | cut -c1-8)"
