#!/usr/bin/env bash
# On a GPU machine (no YADE, no package registry): the CUDA tests, then CPU-vs-CUDA runs of the
# coupled §3.2 flume and the MPM throughput benchmark, with logs, the runs' JSON lines and a
# markdown table in $OUT (or ./gpu-out).
#
#   bash scripts/bench/gpu_run.sh                      # builds build-gpu first (needs .deps/:
#                                                      # scripts/bench/gpu_deps.sh)
#   bash scripts/bench/gpu_run.sh --prebuilt DIR       # test_mpm, test_coupling and mpmsdem-run
#                                                      # built elsewhere (-DMPMSDEM_DRIVER_ONLY=ON
#                                                      # -DMPMSDEM_NATIVE=OFF, sm_90); builds if
#                                                      # they do not start here
#   GPU_RUN_BUDGET=400 bash scripts/bench/gpu_run.sh   # seconds: a stage that would start later
#                                                      # is skipped (and says so)
#   GPU_RUN_STAGES='test_|coarse' bash ...             # only the stages whose names match this
#                                                      # extended regular expression
#
# Stages, most telling first: the whole of test_mpm and test_coupling (the CPU-vs-CUDA
# agreement tests are the ones a machine without a GPU skips); the coarse flume
# (examples/scenes/flume_block.json) over its 1.2 s on the CPU (every core) and on CUDA in double
# and float, and once more in double (CUDA's atomic sums make runs differ: by how much); the
# flume at the paper's resolution (flume_block_full.json): 4,000 steps on the
# CPU and on CUDA, then the whole 2 s on CUDA in double and float (the project's goal: at most
# 2 min on one H100); bench_mpm.py --cuda. Every run is --bench (HDF5 may be missing there): its
# JSON line holds the time, the stage split and each moving block's travel and peak flow force.
set -uo pipefail
cd "$(dirname "$0")/../.."
out=${OUT:-gpu-out}
budget=${GPU_RUN_BUDGET:-100000}
only=${GPU_RUN_STAGES:-.}
prebuilt=""
if [ "${1:-}" = "--prebuilt" ]; then prebuilt=${2:?"--prebuilt needs a folder"}; fi
mkdir -p "$out"
start=$SECONDS
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv | tee "$out/gpu.txt"
grep -m1 'model name' /proc/cpuinfo | tee -a "$out/gpu.txt"
echo "cores: $(nproc); commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)" | tee -a "$out/gpu.txt"

bin=build-gpu
if [ -n "$prebuilt" ] && "$prebuilt/mpmsdem-run" --help > /dev/null 2>&1; then
  bin=$prebuilt
  echo "binaries: $prebuilt (built elsewhere)" | tee -a "$out/gpu.txt"
else
  [ -n "$prebuilt" ] && echo "binaries in $prebuilt do not start here: building" | tee -a "$out/gpu.txt"
  cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DMPMSDEM_DRIVER_ONLY=ON -DMPMSDEM_DEPS="$PWD/.deps" \
    > "$out/configure.log" 2>&1 || { tail -30 "$out/configure.log"; exit 1; }
  cmake --build build-gpu -j "$(nproc)" --target test_mpm test_coupling mpmsdem-run > "$out/build.log" 2>&1 \
    || { tail -40 "$out/build.log"; exit 1; }
fi

# stage NAME SECONDS CMD...: runs CMD under a time limit unless the budget is spent.
stage() {
  local name=$1 limit=$2
  shift 2
  [[ $name =~ $only ]] || return 0
  if (( SECONDS - start + 5 > budget )); then
    echo "== $name: skipped (budget of ${budget} s spent)"
    return
  fi
  echo "== $name ($(( SECONDS - start )) s in)"
  timeout "$limit" bash -c '"$@"' "$name" "$@"
  local rc=$?
  (( rc == 0 )) || echo "== $name: exit $rc$( (( rc == 124 )) && echo ' (time limit)')"
}

# tests: the failures in full, the summary of each
for t in test_mpm test_coupling; do
  stage "$t" 240 bash -c "'$bin/$t' --gtest_output=xml:'$out/$t.xml' > '$out/$t.log' 2>&1; rc=\$?; \
    grep -E '^\[  (FAILED|PASSED|SKIPPED) +\] ([0-9]+ tests?|[^ ]+$)' '$out/$t.log'; grep -B30 '^\[  FAILED  \]' '$out/$t.log' | head -150; exit \$rc"
done

# flume_run NAME SCENE BACKEND PRECISION [ARGS...]: one --bench run, its JSON line in $out/NAME.json
flume_run() {
  local name=$1 scene=$2 backend=$3 precision=$4
  shift 4
  OMP_NUM_THREADS=$(nproc) "$bin/mpmsdem-run" "$scene" --backend "$backend" --precision "$precision" --bench "$@" \
    2> "$out/$name.err" | tail -1 | tee "$out/$name.json"
  local rc=${PIPESTATUS[0]}
  (( rc == 0 )) || tail -5 "$out/$name.err"
  return "$rc"
}
export -f flume_run
export bin out
# flume NAME SECONDS SCENE BACKEND PRECISION [ARGS...]: flume_run as a stage of that name
flume() {
  local name=$1 limit=$2
  shift 2
  stage "$name" "$limit" flume_run "$name" "$@"
}
coarse=examples/scenes/flume_block.json
full=examples/scenes/flume_block_full.json
flume coarse_cpu_double 120 "$coarse" cpu double
flume coarse_cuda_double 120 "$coarse" cuda double
flume coarse_cuda_float 120 "$coarse" cuda float
flume coarse_cuda_double_again 120 "$coarse" cuda double
flume full_cpu_4000 120 "$full" cpu double --steps 4000
flume full_cuda_4000 120 "$full" cuda double --steps 4000
flume full_cuda_double 150 "$full" cuda double
flume full_cuda_float 150 "$full" cuda float
stage bench_mpm 200 python3 scripts/bench/bench_mpm.py --exe "$bin/mpmsdem-run" --cuda --threads "$(nproc)" \
  --gpu-updates 1e9 --markdown "$out/bench.md"
echo "== done in $(( SECONDS - start )) s"
