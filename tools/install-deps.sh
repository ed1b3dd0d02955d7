#!/usr/bin/env bash
# Installs the Debian 12 packages mpmsdem needs, only those that are missing, then the peers'
# virtual environment (.venv-peers/, below). Used by `make demo` / `make test`; cheap when
# everything is there already.
set -euo pipefail
PKGS=(
  build-essential cmake pkg-config
  yade python3-yade libyade
  python3-dev python3-numpy python3-h5py python3-matplotlib python3-pytest
  python3-scipy python3-dask python3-distributed python3-gdal python3-hypothesis
  python3-pytest-xdist   # make test-py: the YADE-level tests JOBS at a time
  libboost-python-dev libeigen3-dev libcgal-dev libgmp-dev libmpfr-dev
  libhdf5-dev nlohmann-json3-dev googletest libgtest-dev
  strace   # scripts/checks/check_fault_injection.py: kills and failed writes at a chosen write call
  clang-14 libclang-rt-14-dev libomp-14-dev   # make fuzz: libFuzzer with ASan + UBSan, OpenMP for clang
  python3-venv   # .venv-peers/ below
)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "mpmsdem: installing missing Debian packages: ${missing[*]}"
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "mpmsdem: need root or sudo to install ${missing[*]}" >&2; exit 1; }
    SUDO=sudo
  fi
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The peers' virtual environment, .venv-peers/ at the repository root (git-ignored): AvaFrame,
# the depth-averaged peer of scripts/validation/avaframe_peer.py and
# tests/python/test_avaframe_peer.py (docs/field.md). A test and benchmark dependency, not a
# runtime one: mpmsdem runs under the system Python with YADE, and AvaFrame runs in this
# environment as a subprocess. Nothing to do when it already imports; a failed download (no
# network) is a warning, not a failed set-up: that comparison is then skipped.
VENV="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/.venv-peers"
AVAFRAME=2.1
if ! "$VENV/bin/python" -c "import importlib.metadata as m, sys; sys.exit(m.version('avaframe') != '$AVAFRAME')" \
    2>/dev/null; then
  echo "mpmsdem: installing avaframe==$AVAFRAME into $VENV (the field comparison's peer, from PyPI)"
  if ! { [ -x "$VENV/bin/python" ] || /usr/bin/python3 -m venv "$VENV"; } \
     || ! "$VENV/bin/python" -m pip install -q --disable-pip-version-check "avaframe==$AVAFRAME"; then
    echo "mpmsdem: WARNING: could not install avaframe==$AVAFRAME into $VENV;" \
         "tests/python/test_avaframe_peer.py will skip its comparison run" >&2
  fi
fi
