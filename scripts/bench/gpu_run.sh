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
#   ... --study DIR                                    # the §5 cases prepared in DIR
#                                                      # (examples/parametric_study.py --prepare)
#                                                      # through the CUDA driver; needs a driver
#                                                      # with HDF5 (scripts/bench/gpu_bundle.sh);
#                                                      # results in $OUT/study.tgz, for --collect
#   ... --study DIR --until 4.5                        # its coupled runs to 4.5 s (the paper's end)
#                                                      # (runs last, with what is left of the budget)
#   ... --sweep DIR                                    # a trade-off sweep prepared in DIR
#                                                      # (tradeoff_sweep_radius.py --prepare: its
#                                                      # run_driver.sh), one run at a time on CUDA:
#                                                      # $OUT/sweep.tgz, for --collect
#   ... --design DIR                                   # the §3.2 cases prepared in DIR
#                                                      # (scripts/validation/paper_flume_design.py
#                                                      # --prepare), likewise: $OUT/design.tgz
#   ... --convergence DIR                              # the §3.2 refinement runs prepared in DIR
#                                                      # (scripts/validation/flume_convergence.py
#                                                      # --prepare): their two legs on CUDA, the
#                                                      # front's profile read there (a driver
#                                                      # with HDF5, as --study); $OUT/
#                                                      # convergence.tgz (no snapshots) to unpack
#                                                      # over DIR here and read with the same
#                                                      # command without --prepare
#   ... --walls DIR                                    # the impact cases prepared in DIR
#                                                      # (scripts/validation/impact_walls.py
#                                                      # --prepare), likewise: $OUT/walls.tgz
#   ... --field SCENE                                  # a field scene's run (examples/field_valley.py
#                                                      # --driver-scene) on CUDA for GPU_FIELD_SECONDS
#                                                      # (300): its simulated time against the wall
#                                                      # clock as the flow develops, and the time
#                                                      # its whole duration would take at the last rate
#   ... --profile-scene FILE                           # (repeatable) where a driver scene's step
#                                                      # goes on CUDA: GPU_PROFILE_STEPS steps
#                                                      # (2000) with --bench --device-stages, and
#                                                      # with its outputs and probes
#   GPU_TEST_FILTER='*uda*' bash ...                   # the tests' gtest filter (default all)
#   GPU_PROFILE_BASELINE=0 bash ...                    # --profile-scene without the baseline's run
#   GPU_BENCH_ARGS='--no-cpu --sizes 1e6,1e7' bash ... # bench_mpm.py's arguments after the stage's
#                                                      # own (a later one wins: a shorter stage)
#   ... --workers N                                    # §5 cases and design cases N at a time
#                                                      # (small scenes leave most of a GPU idle;
#                                                      # default 1; refinement runs and impact
#                                                      # cases take the device one at a time)
#   ... --baseline DIR                                 # an older mpmsdem-run in DIR: the MPM
#                                                      # benchmark and the flume's first 4,000
#                                                      # steps run with it too (new/old speed)
#   GPU_RUN_BUDGET=400 bash scripts/bench/gpu_run.sh   # seconds the whole call may take (default
#                                                      # 560): each stage is cut to what is left of
#                                                      # it and one that would start later is
#                                                      # skipped (and says so), so that the prepared
#                                                      # runs are archived before it ends; give the
#                                                      # call an outer limit of the budget + 30 s
#                                                      # (a call stopped from outside during a stage
#                                                      # archives only when that stage returns)
#   GPU_RUN_STAGES='test_|coarse' bash ...             # only the stages whose names match this
#                                                      # extended regular expression (a call for
#                                                      # prepared runs alone: '^walls$' and so on)
#
# The outputs end up in one archive, $OUT/gpu-run.tgz (also when the command is stopped).
#
# Stages, most telling first: the whole of test_mpm and test_coupling, one after the other (stages
# test_mpm, test_coupling; the CPU-vs-CUDA agreement tests are the ones a machine without a GPU
# skips); the
# prepared §3.2 design (--design), refinement runs (--convergence) and impact cases (--walls); bench_mpm.py --cuda (MPM
# updates/s at 1e5..1e7 points, against the CPU and the baseline); the flume at the paper's
# resolution (flume_block_full.json): 4,000 steps on the CPU and on CUDA (new and baseline: the
# coupling's share of the step is in each JSON line), then the whole 2 s on CUDA in double and
# float (the project's goal: at most 8 s on one H100); the grid's cost against the domain (stage
# sparse_grid: a dam break in its box and in a 1 km x 1 km x 200 m domain); the coarse flume
# (examples/scenes/flume_block.json) over its 1.2 s on the CPU (every core) and on CUDA in double
# and float, and once more in double (are two CUDA runs equal?); the device time of the MPM
# step's stages (--device-stages) on dam breaks and the flume; an Nsight Compute profile of
# the MPM kernels when ncu is found, and an Nsight Systems summary of the flume when nsys is.
# Every run is --bench (HDF5 may be missing there): its JSON
# line holds the time, the stage split and each moving block's travel and peak flow force.
# Binaries from scripts/bench/gpu_bundle.sh bring the shared libraries they need in DIR/lib.
set -uo pipefail
cd "$(dirname "$0")/../.."
out=${OUT:-gpu-out}
budget=${GPU_RUN_BUDGET:-560}
only=${GPU_RUN_STAGES:-.}
prebuilt=""
baseline=""
study=""
design=""
convergence=""
walls=""
sweep=""
until=""
field=""
workers=1
profile=()
while [ $# -gt 0 ]; do
  case $1 in
    --prebuilt) prebuilt=${2:?"--prebuilt needs a folder"}; shift 2 ;;
    --baseline) baseline=${2:?"--baseline needs a folder"}; shift 2 ;;
    --study) study=${2:?"--study needs a folder of prepared cases"}; shift 2 ;;
    --design) design=${2:?"--design needs a folder of prepared cases"}; shift 2 ;;
    --convergence) convergence=${2:?"--convergence needs a folder of prepared runs"}; shift 2 ;;
    --walls) walls=${2:?"--walls needs a folder of prepared cases"}; shift 2 ;;
    --sweep) sweep=${2:?"--sweep needs a folder of prepared runs"}; shift 2 ;;
    --until) until=${2:?"--until needs a time [s]"}; shift 2 ;;
    --field) field=${2:?"--field needs a driver scene"}; shift 2 ;;
    --profile-scene) profile+=("${2:?"--profile-scene needs a driver scene"}"); shift 2 ;;
    --workers) workers=${2:?"--workers needs a number of cases"}; shift 2 ;;
    *) echo "gpu_run.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
mkdir -p "$out"
# Everything the stages write goes, at the end (also when the command is stopped), into one
# archive $out/gpu-run.tgz, the files themselves removed: one file to copy back, however many
# stages ran.
pack() {
  trap - EXIT TERM INT
  (cd "$out" && find . -maxdepth 1 -type f ! -name gpu-run.tgz ! -name .packed | sed 's|^\./||' | sort > .packed &&
    [ -s .packed ] && tar czf gpu-run.tgz -T .packed && xargs rm -f < .packed; rm -f .packed)
  echo "gpu_run.sh: outputs in $out/gpu-run.tgz"
}
trap pack EXIT
trap 'pack; exit 143' TERM INT
start=$SECONDS
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv | tee "$out/gpu.txt"
grep -m1 'model name' /proc/cpuinfo | tee -a "$out/gpu.txt"
echo "cores: $(nproc); commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)" | tee -a "$out/gpu.txt"

bin=build-gpu
# a bundle's own libraries (HDF5 and what it needs), before any of its binaries is started
for d in "$prebuilt" "$baseline"; do
  [ -n "$d" ] && [ -d "$d/lib" ] && export LD_LIBRARY_PATH="$(cd "$d/lib" && pwd)${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
done
# (a baseline folder may hold mpmsdem-run alone and use the bundle's libraries)
if [ -n "$baseline" ] && ! "$baseline/mpmsdem-run" --help > /dev/null 2>&1; then
  echo "gpu_run.sh: no mpmsdem-run that starts in $baseline" >&2
  exit 2
fi
if [ -n "$prebuilt" ] && "$prebuilt/mpmsdem-run" --help > /dev/null 2>&1; then
  bin=$prebuilt
  echo "binaries: $prebuilt (built elsewhere, at $(cat "$prebuilt/COMMIT" 2>/dev/null || echo 'an unrecorded commit'))" |
    tee -a "$out/gpu.txt"
else
  [ -n "$prebuilt" ] && echo "binaries in $prebuilt do not start here: building" | tee -a "$out/gpu.txt"
  cmake -S . -B build-gpu -DCMAKE_BUILD_TYPE=Release -DMPMSDEM_DRIVER_ONLY=ON -DMPMSDEM_DEPS="$PWD/.deps" \
    > "$out/configure.log" 2>&1 || { tail -30 "$out/configure.log"; exit 1; }
  cmake --build build-gpu -j "$(nproc)" --target test_mpm test_coupling mpmsdem-run > "$out/build.log" 2>&1 \
    || { tail -40 "$out/build.log"; exit 1; }
fi

# stage NAME SECONDS CMD...: runs CMD under a time limit, SECONDS or what is left of the budget
# (less 10 s to archive), unless less than 20 s is left; CMD finds its limit in STAGE_LIMIT.
stage() {
  local name=$1 limit=$2
  shift 2
  [[ $name =~ $only ]] || return 0
  local left=$(( budget - (SECONDS - start) - 10 ))
  if (( left < 20 )); then
    echo "== $name: skipped (budget of ${budget} s spent)"
    return
  fi
  (( limit > left )) && limit=$left
  echo "== $name ($(( SECONDS - start )) s in, at most $limit s)"
  STAGE_LIMIT=$limit timeout "$limit" bash -c '"$@"' "$name" "$@"
  local rc=$?
  (( rc == 0 )) || echo "== $name: exit $rc$( (( rc == 124 )) && echo ' (time limit)')"
}

# tests: the failures in full, the summary of each (one suite at a time: two OpenMP suites side
# by side on the machine's cores took 171 s for a test of seconds)
for t in test_mpm test_coupling; do
  stage "$t" 240 bash -c "OMP_WAIT_POLICY=PASSIVE '$bin/$t' --gtest_filter='${GPU_TEST_FILTER:-*}' \
    --gtest_output=xml:'$out/$t.xml' > '$out/$t.log' 2>&1; rc=\$?; \
    grep -E '^\[  (FAILED|PASSED|SKIPPED) +\] ([0-9]+ tests?|[^ ]+$)' '$out/$t.log'; grep -B30 '^\[  FAILED  \]' '$out/$t.log' | head -150; exit \$rc"
done
export bin out workers baseline

# prepared cases through the CUDA driver, WORKERS at a time (a case run before is skipped: a
# second call goes on), their outputs but the particle snapshots and restart points in
# $out/NAME.tgz, written also when the runs are stopped 15 s before the stage's limit (the cases
# not finished have no done.json/run.json and are run again by the next call; a refinement run
# whose free leg's state did not come back runs that leg again): prepared_run NAME WORKERS DIR
# SCRIPT [OPTION...]
prepared_run() {
  local name=$1 n=$2 dir=$3 script=$4 limit=$(( STAGE_LIMIT - 15 ))
  shift 4
  timeout -k 5 "$limit" python3 "$script" --run-prepared "$dir" --backend cuda --exe "$bin/mpmsdem-run" \
    --workers "$n" --threads "$(( $(nproc) / n > 0 ? $(nproc) / n : 1 ))" "$@" 2>&1 | tee "$out/$name.log"
  local rc=${PIPESTATUS[0]}
  (( rc == 124 )) && echo "$name: stopped at its ${limit} s; the cases above that say so are done"
  tar czf "$out/$name.tgz" --exclude=mpm.snapshots --exclude='*.restart' --exclude='*.checkpoint.json' \
    -C "$(dirname "$dir")" "$(basename "$dir")"
  return "$rc"
}
export -f prepared_run
[ -n "$design" ] && stage design 420 prepared_run design "$workers" "$design" scripts/validation/paper_flume_design.py
# (the §3.2 cube at Δx 0.0025 m to 0.4 s: 6,144,000 points, about 37,000 steps of 1.29e-5 s in the two legs;
# at the rates measured on an H200 in double, 1.48e9 particle-updates/s and the coupling's 0.63 of the MPM step
# (docs/benchmarks.md), about 4 min: an estimate, not a measurement)
[ -n "$convergence" ] && stage convergence 550 prepared_run convergence 1 "$convergence" \
  scripts/validation/flume_convergence.py
[ -n "$walls" ] && stage walls 420 prepared_run walls 1 "$walls" scripts/validation/impact_walls.py
# sweep_run DIR: a prepared trade-off sweep's runs one after another on CUDA (side by side they
# only take turns on the GPU), their logs and coupled.h5 in $out/sweep.tgz also when stopped
# (15 s before the stage's limit)
sweep_run() {
  local dir=$1 rc
  MPMSDEM_RUN="$bin/mpmsdem-run" JOBS=1 OMP_NUM_THREADS=$(nproc) timeout -k 5 $(( STAGE_LIMIT - 15 )) \
    bash "$dir/run_driver.sh" 2>&1 |
    tee "$out/sweep.log"
  rc=${PIPESTATUS[0]}
  tar czf "$out/sweep.tgz" --exclude='*.snapshots' --exclude='*.restart' -C "$(dirname "$dir")" "$(basename "$dir")"
  return "$rc"
}
export -f sweep_run
[ -n "$sweep" ] && stage sweep 420 sweep_run "$sweep"

# flume_run NAME SCENE BACKEND PRECISION [ARGS...]: one --bench run, its JSON line in $out/NAME.json
# (FLUME_EXE: another mpmsdem-run)
flume_run() {
  local name=$1 scene=$2 backend=$3 precision=$4
  shift 4
  OMP_NUM_THREADS=$(nproc) "${FLUME_EXE:-$bin/mpmsdem-run}" "$scene" --backend "$backend" --precision "$precision" \
    --bench "$@" 2> "$out/$name.err" | tail -1 | tee "$out/$name.json"
  local rc=${PIPESTATUS[0]}
  (( rc == 0 )) || tail -5 "$out/$name.err"
  return "$rc"
}
export -f flume_run
# flume NAME SECONDS SCENE BACKEND PRECISION [ARGS...]: flume_run as a stage of that name
flume() {
  local name=$1 limit=$2
  shift 2
  stage "$name" "$limit" flume_run "$name" "$@"
}
coarse=examples/scenes/flume_block.json
full=examples/scenes/flume_block_full.json
base_args=()
[ -n "$baseline" ] && base_args=(--baseline-exe "$baseline/mpmsdem-run")
stage bench_mpm 240 python3 scripts/bench/bench_mpm.py --exe "$bin/mpmsdem-run" --cuda --threads "$(nproc)" \
  --cpu-precisions double --gpu-updates 1e9 --markdown "$out/bench.md" --json "$out/bench.json" "${base_args[@]}" ${GPU_BENCH_ARGS:-}
flume full_cpu_4000 120 "$full" cpu double --steps 4000
flume full_cuda_4000 60 "$full" cuda double --steps 4000
[ -n "$baseline" ] && FLUME_EXE=$baseline/mpmsdem-run flume full_cuda_4000_baseline 60 "$full" cuda double --steps 4000
# same_results LABEL A B [KEY...]: whether two --bench JSON lines hold the same results, their
# timings and the KEYs aside (the differing keys if not), and each run's coupling share
same_results() {
  python3 - "$@" <<'PY'
import json, sys
label, (a, b), ignored = sys.argv[1], (json.load(open(f)) for f in sys.argv[2:4]), set(sys.argv[4:])
drop = lambda r: {k: v for k, v in r.items() if "second" not in k and "per_s" not in k and k not in ignored}
da, db = drop(a), drop(b)
print(label + ":", "the same results" if da == db else
      "differ: %s" % {k: (da.get(k), db.get(k)) for k in set(da) | set(db) if da.get(k) != db.get(k)})
if all("coupling" in r.get("stage_seconds", {}) for r in (a, b)):
    new, old = a["stage_seconds"], b["stage_seconds"]
    print("coupling / MPM step: %.2f and %.2f; coupling time %.2f of the second's" % (
        new["coupling"] / new["mpm"], old["coupling"] / old["mpm"], new["coupling"] / old["coupling"]))
PY
}
export -f same_results
# The new build against the baseline on the same 4,000 steps (its memory may differ)
[ -n "$baseline" ] && stage baseline_same 10 same_results "the flume's 4,000 CUDA steps, new against the baseline" \
  "$out/full_cuda_4000.json" "$out/full_cuda_4000_baseline.json" bytes_per_particle
# The grid's cost against the domain on CUDA (bench_sparse_grid.py): a dam break of GPU_SPARSE_POINTS
# (1e7) points at Δx 1 m in its box and in a 1 km x 1 km x 200 m domain, 300 steps, new against
# the baseline (whose grid held the whole box); its table in $out/sparse_grid.md
stage sparse_grid 240 bash -c "python3 scripts/bench/bench_sparse_grid.py --exe '$bin/mpmsdem-run' --backend cuda \
  --points '${GPU_SPARSE_POINTS:-1e7}' --steps 300 --threads '$(nproc)' ${baseline:+--baseline-exe '$baseline/mpmsdem-run'} \
  2>&1 | tee '$out/sparse_grid.md'"
flume full_cuda_double 120 "$full" cuda double
flume full_cuda_float 120 "$full" cuda float
flume coarse_cpu_double 120 "$coarse" cpu double
flume coarse_cuda_double 60 "$coarse" cuda double
flume coarse_cuda_double_again 60 "$coarse" cuda double
flume coarse_cuda_float 60 "$coarse" cuda float
# Equal JSON lines but for the timings: the two CUDA runs gave the same travels and forces.
stage cuda_repeat 10 same_results "two CUDA double runs of the coarse flume" "$out/coarse_cuda_double.json" \
  "$out/coarse_cuda_double_again.json"
# dam_scene SIZE: bench_mpm.py's dam break of about SIZE points, written to $out/damSIZE.json
dam_scene() {
  python3 -c "import json, sys; sys.path.insert(0, 'scripts/bench'); import bench_mpm; \
json.dump(bench_mpm.dam_break_scene($1)[0], open('$out/dam$1.json', 'w'))"
}
export -f dam_scene

# Where a step's device time goes (mpmsdem-run --device-stages: the lists, sort, P2G, grid, G2P
# and columns by device events) on dam breaks of 1e5, 1e6 and 1e7 points in float (the 1e7 one
# with the baseline too) and on the flume's first 4,000 steps, against the step loop's wall time.
device_stages() {
  local files=()
  for size in 100000 1000000 10000000; do
    dam_scene "$size" || return 1
    "$bin/mpmsdem-run" "$out/dam$size.json" --backend cuda --precision float --bench --device-stages --steps 500 \
      2> /dev/null | tail -1 > "$out/stages_dam$size.json"
    files+=("$out/stages_dam$size.json")
  done
  if [ -n "$baseline" ]; then
    "$baseline/mpmsdem-run" "$out/dam10000000.json" --backend cuda --precision float --bench --device-stages \
      --steps 500 2> /dev/null | tail -1 > "$out/stages_dam10000000_baseline.json"
    files+=("$out/stages_dam10000000_baseline.json")
  fi
  OMP_NUM_THREADS=$(nproc) "$bin/mpmsdem-run" "$full" --backend cuda --precision double --bench --device-stages \
    --steps 4000 2> /dev/null | tail -1 > "$out/stages_full.json"
  python3 - "${files[@]}" "$out"/stages_full.json <<'PY'
import json, sys
for f in sys.argv[1:]:
    r = json.load(open(f))
    d = r.get("device_stage_seconds", {})
    extra = " mpm stage %.3f s coupling %.3f s" % (r["stage_seconds"]["mpm"], r["stage_seconds"]["coupling"]) if "stage_seconds" in r else ""
    if "coupling_stage_seconds" in r:
        extra += " (coupling: %s)" % ", ".join("%s %.3f" % kv for kv in r["coupling_stage_seconds"].items())
    print("%s: %d points x %d steps, loop %.3f s%s; device: %s (sum %.3f s)" % (f.split("/")[-1], r["particles"], r["steps"],
          r["seconds"], extra, ", ".join("%s %.3f" % kv for kv in d.items()), sum(d.values())))
PY
}
export -f device_stages
export full

# ncu_profile EXE NAME: Nsight Compute on the MPM kernels of one step (the third) of a 1e6-point
# dam break in float: duration, throughput against the device's peak, occupancy
ncu_profile() {
  dam_scene 1000000 || return 1
  "$ncu" --clock-control none -k 'regex:p2g|g2p|binKernel|rangesKernel|gridKernel|Onesweep|Histogram' --launch-skip 26 --launch-count 13 \
    --section SpeedOfLight --section Occupancy "$1" "$out/dam1000000.json" --backend cuda --precision float --bench \
    --steps 4 > "$out/ncu_$2.txt" 2>&1
  grep -E '^  [A-Za-z_].*[(]|Duration|Memory Throughput|DRAM Throughput|Compute [(]SM[)] Throughput|Achieved Occupancy' \
    "$out/ncu_$2.txt" | head -100
}
stage device_stages 120 device_stages
ncu=$(command -v ncu || ls /usr/local/cuda/bin/ncu 2> /dev/null || true)
export -f ncu_profile
export ncu
if [ -n "$ncu" ]; then
  stage ncu_new 90 ncu_profile "$bin/mpmsdem-run" new
  [ -n "$baseline" ] && stage ncu_baseline 90 ncu_profile "$baseline/mpmsdem-run" baseline
else
  echo "== ncu: skipped (no ncu on this machine)"
fi
# Nsight Systems on 2,000 steps of the flume at the paper's resolution: time per CUDA API call
# and per kernel over the coupled step (what the small scene spends besides the kernels).
nsys=$(command -v nsys || ls /usr/local/cuda/bin/nsys 2> /dev/null || true)
if [ -n "$nsys" ]; then
  stage nsys_flume 120 bash -c "'$nsys' profile --stats=true --force-overwrite=true -o '$out/flume' \
    '$bin/mpmsdem-run' '$full' --backend cuda --precision double --bench --steps 2000 > '$out/nsys_flume.txt' 2>&1; \
    grep -A14 -E 'cuda_api_sum|cuda_gpu_kern_sum' '$out/nsys_flume.txt' | cut -c1-160"
else
  echo "== nsys_flume: skipped (no nsys on this machine)"
fi
# scene_profile FILE: where the step of a driver scene goes on CUDA (the scene's precision);
# with --baseline, the baseline's --bench run of the same steps right after, and new/old
scene_profile() {
  local scene=$1 steps=${GPU_PROFILE_STEPS:-2000} name
  name=$(basename "$(dirname "$scene")")_$(basename "$scene" .json)
  "$bin/mpmsdem-run" "$scene" --backend cuda --bench --device-stages --steps "$steps" 2> /dev/null | tail -1 \
    > "$out/profile_$name.json" || return 1
  if [ -n "$baseline" ] && [ "${GPU_PROFILE_BASELINE:-1}" = 1 ]; then
    "$baseline/mpmsdem-run" "$scene" --backend cuda --bench --device-stages --steps "$steps" 2> /dev/null | tail -1 \
      > "$out/profile_${name}_baseline.json" || return 1
    python3 - "$out/profile_$name.json" "$out/profile_${name}_baseline.json" <<'PY'
import json, sys
new, old = (json.load(open(f)) for f in sys.argv[1:3])
dn, do = new.get("device_stage_seconds", {}), old.get("device_stage_seconds", {})
print("%s: step loop new %.3f s, baseline %.3f s: new/old speed %.2f; device stages new/baseline: %s" % (
    sys.argv[1].split("/")[-1], new["seconds"], old["seconds"], old["seconds"] / new["seconds"],
    ", ".join("%s %.3f/%.3f" % (k, dn[k], do.get(k, float("nan"))) for k in dn)))
PY
  fi
  local t0=$SECONDS
  "$bin/mpmsdem-run" "$scene" --backend cuda --steps "$steps" --out "/tmp/profile_$name" > "$out/profile_$name.log" 2>&1 \
    || { tail -5 "$out/profile_$name.log"; return 1; }
  python3 - "$out/profile_$name.json" "$(( SECONDS - t0 ))" "$(grep -a 'step loop' "$out/profile_$name.log" | tail -1)" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
d = r.get("device_stage_seconds", {})
print("%s: %d points x %d steps --bench: loop %.2f s (%.3g upd/s; %s); device %s (sum %.2f s); coupling parts %s; "
      "with outputs: %s s wall, %s" % (
    sys.argv[1].split("/")[-1], r["particles"], r["steps"], r["seconds"], r["particle_updates_per_s"],
    ", ".join("%s %.2f" % kv for kv in r.get("stage_seconds", {}).items()),
    ", ".join("%s %.2f" % kv for kv in d.items()), sum(d.values()),
    ", ".join("%s %.3f" % kv for kv in r.get("coupling_stage_seconds", {}).items()) or "-", sys.argv[2], sys.argv[3]))
PY
}
export -f scene_profile
for f in "${profile[@]}"; do
  stage "profile_$(basename "$(dirname "$f")")" 120 scene_profile "$f"
done

# field_run SCENE SECONDS: the scene on CUDA (--bench: no outputs, progress lines on stderr)
# stopped after SECONDS; each progress line with the wall-clock seconds since the start in
# $out/field.log, then the simulated time reached against the wall time, and the scene's whole
# duration at the rate of the last minute
field_run() {
  local scene=$1 t0=$SECONDS
  timeout -s TERM "$2" "$bin/mpmsdem-run" "$scene" --backend cuda --bench 2>&1 >/dev/null |
    while IFS= read -r line; do echo "$(( SECONDS - t0 )) $line"; done > "$out/field.log"
  python3 - "$out/field.log" "$scene" <<'PY'
import json, re, sys
rows = []
for line in open(sys.argv[1]):
    m = re.match(r"(\d+) \[.*?\] t=([0-9.eE+-]+) s step=(\d+) dt=([0-9.eE+-]+) s", line)
    if m:
        rows.append((int(m.group(1)), float(m.group(2)), int(m.group(3)), float(m.group(4))))
if not rows:
    sys.exit("field: no progress line (the log's end:\n%s)" % "".join(open(sys.argv[1]).readlines()[-5:]))
duration = json.load(open(sys.argv[2]))["run"]["duration"]
for w, t, n, dt in rows[:: max(1, len(rows) // 12)] + rows[-1:]:
    print("field: %4d s wall: t %.3f s, step %d, dt %.3g s" % (w, t, n, dt))
w1, t1 = rows[-1][0], rows[-1][1]
past = [r for r in rows if r[0] <= w1 - 60] or rows[:1]
w0, t0 = past[-1][0], past[-1][1]
if t1 > t0 and w1 > w0:
    rate = (t1 - t0) / (w1 - w0)
    print("field: %.3f s simulated in %d s; the last %d s at %.4f s per wall second: %.0f s of %.0f s to go, "
          "%.1f h in all at that rate" % (t1, w1, w1 - w0, rate, duration - t1, duration, (w1 + (duration - t1) / rate) / 3600))
PY
}
export -f field_run
[ -n "$field" ] && stage field $(( ${GPU_FIELD_SECONDS:-300} + 30 )) field_run "$field" "${GPU_FIELD_SECONDS:-300}"

# the §5 cases last: they take what is left of the budget (a case not finished by then is run
# again from its start by the next call)
[ -n "$study" ] && stage study "$budget" prepared_run study "$workers" "$study" examples/parametric_study.py \
  ${until:+--until "$until"}
echo "== done in $(( SECONDS - start )) s"
