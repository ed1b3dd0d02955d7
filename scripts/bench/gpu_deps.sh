#!/usr/bin/env bash
# Copies the header-only dependencies (Eigen, nlohmann-json) and GoogleTest's sources from
# this machine's Debian packages into .deps/ (git-ignored), so that a GPU machine with no
# package registry can build the solvers and the driver (MPMSDEM_DRIVER_ONLY). Then copy the
# repository with .deps/ to the GPU machine and run scripts/bench/gpu_run.sh there.
set -euo pipefail
cd "$(dirname "$0")/../.."
bash tools/install-deps.sh
rm -rf .deps && mkdir -p .deps/include
cp -r /usr/include/eigen3 .deps/include/
cp -r /usr/include/nlohmann .deps/include/
cp -r /usr/src/googletest .deps/googletest
du -sh .deps
