#!/usr/bin/env bash
# On a GPU machine (no YADE, no package registry; see scripts/bench/gpu_deps.sh): builds the
# solvers and the driver with CUDA (MPMSDEM_DRIVER_ONLY), runs test_mpm and test_coupling (the
# CPU vs CUDA agreement tests included) and the throughput benchmark, and leaves the logs and a
# markdown table in $OUT (or ./gpu-out).
set -uo pipefail
cd "$(dirname "$0")/../.."
out=${OUT:-gpu-out}
mkdir -p "$out"
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv | tee "$out/gpu.txt"
cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DMPMSDEM_DRIVER_ONLY=ON -DMPMSDEM_DEPS="$PWD/.deps" \
  > "$out/configure.log" 2>&1 || { tail -30 "$out/configure.log"; exit 1; }
cmake --build build-gpu -j "$(nproc)" --target test_mpm test_coupling mpmsdem-run > "$out/build.log" 2>&1 \
  || { tail -40 "$out/build.log"; exit 1; }
build-gpu/test_mpm 2>&1 | tee "$out/test_mpm.log" | tail -25
build-gpu/test_coupling 2>&1 | tee "$out/test_coupling.log" | tail -25
python3 scripts/bench/bench_mpm.py --build build-gpu --cuda --markdown "$out/bench.md" 2>&1 | tee "$out/bench.log"
# The coupled §3.2 flume at the paper's resolution (examples/scenes/flume_block_full.json,
# written by examples/flume_block.py --full --driver-scene): the first 4,000 steps on the CPU
# (every core) and on CUDA, for the ratio in one command, then the whole 2 s on CUDA (the
# project's goal: at most 2 min on one H100); --bench: no outputs (HDF5 may be missing there).
scene=examples/scenes/flume_block_full.json
for backend in cpu cuda; do
  OMP_NUM_THREADS=$(nproc) build-gpu/mpmsdem-run "$scene" --backend "$backend" --bench --steps 4000 \
    2>"$out/flume_${backend}_4000.err" | tail -1 | tee "$out/flume_${backend}_4000.json"
done
build-gpu/mpmsdem-run "$scene" --backend cuda --bench 2>"$out/flume_full_cuda.err" | tail -1 \
  | tee "$out/flume_full_cuda.json"
