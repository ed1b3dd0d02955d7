#!/usr/bin/env bash
# Installs the Debian 12 packages mpmsdem needs, only those that are missing.
# Used by `make demo` / `make test`; cheap when everything is there already.
set -euo pipefail
PKGS=(
  build-essential cmake pkg-config
  yade python3-yade libyade
  python3-dev python3-numpy python3-h5py python3-matplotlib python3-pytest
  python3-scipy python3-dask python3-distributed python3-gdal python3-hypothesis
  libboost-python-dev libeigen3-dev libcgal-dev libgmp-dev libmpfr-dev
  libhdf5-dev nlohmann-json3-dev googletest libgtest-dev
  strace   # scripts/checks/check_fault_injection.py: kills and failed writes at a chosen write call
)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "mpmsdem: installing missing Debian packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "mpmsdem: need root or sudo to install ${missing[*]}" >&2; exit 1; }
  SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
