#!/usr/bin/env bash
# Builds, here, what scripts/bench/gpu_run.sh runs on a GPU machine (which has no package
# registry and may lack HDF5): the driver mpmsdem-run, test_mpm and test_coupling, driver-only,
# with the CUDA backend for sm_90 (H100/H200), portable code (no -march=native) and HDF5 (so
# that the driver writes its outputs: flow probes, coupled.h5, restarts). The shared libraries
# they need beyond the C library go into DIR/lib; gpu_run.sh puts that folder on
# LD_LIBRARY_PATH. Carry DIR to the GPU machine with the repository and run
#   bash scripts/bench/gpu_run.sh --prebuilt DIR [--study PREPARED]
#
#   bash scripts/bench/gpu_bundle.sh [DIR]        (default build-gpubin/new; builds in build-gpunew)
set -euo pipefail
cd "$(dirname "$0")/../.."
dir=${1:-build-gpubin/new}
command -v nvcc > /dev/null || { echo "gpu_bundle.sh: no nvcc on the PATH (the CUDA toolkit)" >&2; exit 2; }
[ -d .deps/include ] || bash scripts/bench/gpu_deps.sh
# (a build folder configured without HDF5 keeps that choice in its cache: cleared here)
mkdir -p build-gpunew
cmake -S . -B build-gpunew -DCMAKE_DISABLE_FIND_PACKAGE_HDF5=OFF \
  -DCMAKE_BUILD_TYPE=Release -DMPMSDEM_DRIVER_ONLY=ON -DMPMSDEM_NATIVE=OFF -DMPMSDEM_DEPS="$PWD/.deps" \
  > build-gpunew/configure.log
grep 'mpmsdem: ' build-gpunew/configure.log
grep -q 'mpmsdem: HDF5 outputs ON' build-gpunew/configure.log ||
  { echo "gpu_bundle.sh: HDF5 not found (libhdf5-dev): the GPU driver would write no outputs" >&2; exit 2; }
cmake --build build-gpunew -j "$(nproc)" --target mpmsdem-run test_mpm test_coupling
rm -rf "$dir" && mkdir -p "$dir/lib"
for b in mpmsdem-run test_mpm test_coupling; do
  cp "build-gpunew/$b" "$dir/" && strip "$dir/$b"
done
# the sources they were built from, for the results' records (the GPU machine's checkout may be newer)
echo "$(git rev-parse --short HEAD)$(git diff --quiet HEAD -- pkg apps tests CMakeLists.txt || echo ' with changes')" > "$dir/COMMIT"
# every library the binaries load, except the C library's own (the GPU machine's must serve:
# a copied libc would not match its loader) and the CUDA driver (the machine's own)
ldd "$dir"/mpmsdem-run "$dir"/test_mpm "$dir"/test_coupling | awk '$2 == "=>" && $3 ~ /^\// {print $3}' | sort -u |
  grep -Ev '/(libc|libm|libpthread|libdl|librt|libresolv|ld-linux[^/]*|libcuda)\.so' |
  while read -r lib; do cp -L "$lib" "$dir/lib/"; done
# the driver must start with those libraries alone beside the C library
missing=$(LD_LIBRARY_PATH="$PWD/$dir/lib" ldd "$dir/mpmsdem-run" | grep 'not found' || true)
[ -z "$missing" ] || { echo "gpu_bundle.sh: unresolved: $missing" >&2; exit 1; }
"$dir/mpmsdem-run" --help > /dev/null 2>&1 || LD_LIBRARY_PATH="$PWD/$dir/lib" "$dir/mpmsdem-run" --help > /dev/null
du -sh "$dir" "$dir/lib"
echo "gpu_bundle.sh: $dir ready (carry it; on the GPU machine: bash scripts/bench/gpu_run.sh --prebuilt $dir)"
