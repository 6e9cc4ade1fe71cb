#!/usr/bin/env bash
# Fuzzes every reader of untrusted input with libFuzzer + ASan + UBSan for a bounded time:
# the sensor readers, model files (dynahand's and the authors'), scene files, pose JSON lines,
# .pose files, tracked-pose / keypoint JSON lines and the viewer's client messages (fuzz/,
# docs/formats.md "Fuzzing"). Not part of the default build or CI test run.
# Usage: scripts/fuzz.sh [SECONDS] [TARGET...]   (default 600 s each, every target)
#   TARGET: sensor_readers model_json model_intel scene pose_jsonl intel_pose track_jsonl
#           viewer_messages (the fuzz_ prefix may be given too).
# Each target runs SECONDS, two at a time at most (FUZZ_PARALLEL=1 for one at a time),
# with its dictionary from fuzz/dicts.
# Installs clang if missing. Builds in build/fuzz; per target the corpus grows in
# build/fuzz/corpus/TARGET, crashes land in build/fuzz/artifacts/TARGET, the log is
# build/fuzz/logs/TARGET.log. Prints and writes to build/fuzz/summary.txt one line per
# target (executions, edge coverage, new units, result). Exits non-zero on any crash, hang
# or out-of-memory, naming the reproducer; rerun one with build/fuzz/fuzz_TARGET FILE.
set -euo pipefail
cd "$(dirname "$0")/.."

all_targets=(sensor_readers model_json model_intel scene pose_jsonl intel_pose track_jsonl
             viewer_messages)
seconds=${1:-600}
if [[ ! $seconds =~ ^[0-9]+$ ]] || (( seconds < 1 )); then
  echo "fuzz.sh: SECONDS must be a positive whole number, got '$seconds'" >&2
  exit 2
fi
shift || true
targets=()
for t in "$@"; do
  t=${t#fuzz_}
  if [[ " ${all_targets[*]} " != *" $t "* ]]; then
    echo "fuzz.sh: unknown target '$t' (known: ${all_targets[*]})" >&2
    exit 2
  fi
  targets+=("$t")
done
(( ${#targets[@]} > 0 )) || targets=("${all_targets[@]}")
parallel=${FUZZ_PARALLEL:-2}
if [[ ! $parallel =~ ^[12]$ ]]; then
  echo "fuzz.sh: FUZZ_PARALLEL must be 1 or 2, got '$parallel'" >&2
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
cmake --build "$build" --target "${targets[@]/#/fuzz_}" make_sensor_seeds make_seeds \
  -j "${FUZZ_BUILD_JOBS:-$(nproc)}"

# Seeds: written by the seed programs, plus the repository's example files and, when the
# shared data folder is there, the original authors' model and a few of their poses (read
# from ../shared, never copied into the repository).
seeds=$build/seeds
rm -rf "$seeds"
"$build/make_sensor_seeds" "$seeds/sensor_readers" >/dev/null
"$build/make_seeds" "$seeds" >/dev/null
mkdir -p "$seeds/scene"
cp examples/scenes/*.json "$seeds/scene/"
cp tests/model/data/*.json "$seeds/model_json/"
shared=../shared/data/intel
if [[ -f $shared/model_hand.json ]]; then
  cp "$shared/model_hand.json" "$seeds/model_intel/authors-model_hand.json"
  head -n 3 "$shared/hand_data_example.pose" > "$seeds/intel_pose/authors-example.pose"
fi

# Dictionaries (fuzz/dicts): each target's field names and tokens, plus JSON's for the JSON
# readers.
mkdir -p "$build/dicts"
for t in "${targets[@]}"; do
  rm -f "$build/dicts/$t.dict"
  [[ -f fuzz/dicts/$t.dict ]] || continue
  case $t in
    intel_pose) cp "fuzz/dicts/$t.dict" "$build/dicts/$t.dict" ;;
    *) cat fuzz/dicts/json.dict "fuzz/dicts/$t.dict" >"$build/dicts/$t.dict" ;;
  esac
done

mkdir -p "$build/logs"
: > "$build/summary.txt.part"
echo "fuzz.sh: fuzzing ${targets[*]} for $seconds s each, $parallel at a time"

# Runs one target; its one-line result goes to $build/logs/TARGET.result.
run_target() {
  local t=$1 corpus=$build/corpus/$1 artifacts=$build/artifacts/$1 log=$build/logs/$1.log
  mkdir -p "$corpus" "$artifacts"
  # A seed longer than -max_len would be cut short: allow the longest seed.
  local max_len=65536 longest
  longest=$(find "$seeds/$t" -type f -printf '%s\n' | sort -n | tail -n 1)
  (( ${longest:-0} > max_len )) && max_len=$longest
  local dict=()
  [[ -f $build/dicts/$t.dict ]] && dict=(-dict="$build/dicts/$t.dict")
  local status=0
  # -rss_limit_mb: a reader asking for huge buffers is a bug too (also caps single mallocs).
  "$build/fuzz_$t" "$corpus" "$seeds/$t" -max_total_time="$seconds" -timeout=10 \
    -rss_limit_mb=2048 -max_len="$max_len" -artifact_prefix="$artifacts/" \
    -print_final_stats=1 "${dict[@]}" >"$log" 2>&1 || status=$?
  local execs cov units result
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  units=$(sed -n 's/^stat::new_units_added: *//p' "$log" | tail -n 1)
  cov=$( (grep -o 'cov: [0-9]*' "$log" || true) | tail -n 1 | sed 's/cov: //')
  if (( status == 0 )); then
    result=ok
  else
    local reproducer
    reproducer=$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$log" | tail -n 1)
    result="FAILED (status $status; reproducer ${reproducer:-none written}; log $log)"
  fi
  printf '%-16s execs %10s  cov %6s  new_units %6s  %s\n' "$t" "${execs:-?}" "${cov:-?}" \
    "${units:-?}" "$result" >"$build/logs/$t.result"
}

running=0
for t in "${targets[@]}"; do
  if (( running >= parallel )); then
    wait -n || true
    running=$((running - 1))
  fi
  rm -f "$build/logs/$t.result"
  run_target "$t" &
  running=$((running + 1))
done
wait || true

failed=0
for t in "${targets[@]}"; do
  if [[ ! -f $build/logs/$t.result ]]; then
    printf '%-16s FAILED (no result; log %s)\n' "$t" "$build/logs/$t.log" >"$build/logs/$t.result"
  fi
  line=$(cat "$build/logs/$t.result")
  echo "$line" >>"$build/summary.txt.part"
  [[ $line == *FAILED* ]] && failed=1
done
mv "$build/summary.txt.part" "$build/summary.txt"
cat "$build/summary.txt"
if (( failed )); then
  echo "fuzz.sh: a target crashed, hung or ran out of memory (see above; summary in $build/summary.txt)" >&2
  exit 1
fi
echo "fuzz.sh: finished, no crash found in $seconds s per target (summary in $build/summary.txt)"
