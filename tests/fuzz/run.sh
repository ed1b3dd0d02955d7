#!/usr/bin/env bash
# Replays the corpus of every libFuzzer target, then fuzzes each for a while (make fuzz).
#   tests/fuzz/run.sh BUILD_DIR [SECONDS [JOBS]]
# BUILD_DIR holds the fuzz_* executables (cmake -DMPMSDEM_FUZZ=ON, see CMakeLists.txt).
# Replay: each file of tests/fuzz/corpus/<target>/ once; any report fails. Fuzzing: SECONDS per
# target (0: replay only), JOBS targets at a time, one process each; new inputs go to
# BUILD_DIR/fuzz-out/<target>.new (the checked-in corpus is read, never written), a crashing
# input to BUILD_DIR/fuzz-out/<target>.crash-* (minimise it with -minimize_crash=1 and add it to
# the corpus once fixed). Exit status non-zero when any target reported something.
set -uo pipefail
build=${1:?usage: run.sh BUILD_DIR [SECONDS [JOBS]]}
seconds=${2:-20}
jobs=${3:-1}
here=$(cd "$(dirname "$0")" && pwd)
out=$build/fuzz-out
rm -rf "$out"
mkdir -p "$out"
targets=()
for c in "$here"/corpus/*/; do
  t=$(basename "$c")
  [ -x "$build/$t" ] || { echo "fuzz: $build/$t missing (build the fuzz_targets target)" >&2; exit 1; }
  targets+=("$t")
done

one() {
  local t=$1 build=$2 seconds=$3 here=$4 out=$5
  local corpus=$here/corpus/$t dict=()
  [ -f "$here/$t.dict" ] && dict=(-dict="$here/$t.dict")
  local opts=(-timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 -artifact_prefix="$out/$t.")
  local files=("$corpus"/*)
  if ! "$build/$t" "${opts[@]}" "${files[@]}" > "$out/$t.replay.log" 2>&1; then
    echo "fuzz: $t: replaying tests/fuzz/corpus/$t failed (log: $out/$t.replay.log):"
    grep -E "ERROR|runtime error|SUMMARY|Running:" "$out/$t.replay.log" | tail -5
    return 1
  fi
  local line="fuzz: $t: ${#files[@]} corpus files replayed"
  if [ "$seconds" -gt 0 ]; then
    mkdir -p "$out/$t.new"
    if ! "$build/$t" "${opts[@]}" "${dict[@]}" -max_total_time="$seconds" -print_final_stats=1 \
        "$out/$t.new" "$corpus" > "$out/$t.fuzz.log" 2>&1; then
      echo "fuzz: $t: FOUND a defect (log: $out/$t.fuzz.log):"
      grep -E "ERROR|runtime error|SUMMARY|Test unit written|terminate|what\(\)" "$out/$t.fuzz.log" | tail -6
      return 1
    fi
    line+=", $(grep -o 'number_of_executed_units: [0-9]*' "$out/$t.fuzz.log" | grep -o '[0-9]*') executions in ${seconds} s"
  fi
  echo "$line"
}
export -f one
printf '%s\n' "${targets[@]}" | xargs -P "$jobs" -I{} bash -c 'one "$@"' _ {} "$build" "$seconds" "$here" "$out"
