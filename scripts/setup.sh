#!/usr/bin/env bash
# Sets tactus up on Debian 12: installs the Debian packages it needs (only those missing, so a
# re-run installs nothing), configures once, then builds incrementally.
# Environment: TACTUS_BUILD_DIR (default build/), TACTUS_CMAKE_ARGS (extra configure flags).
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BUILD=${TACTUS_BUILD_DIR:-$ROOT/build}

PACKAGES=(
  g++ cmake ninja-build pkg-config git
  libeigen3-dev libhdf5-dev libgmsh-dev libvtk9-dev libcgal-dev libopencv-dev libtbb-dev
  libcli11-dev libtomlplusplus-dev nlohmann-json3-dev libgtest-dev libgdcm-dev zlib1g-dev libmetis-dev
  libopenmpi-dev openmpi-bin
  xvfb xauth chromium
  python3 python3-numpy python3-h5py python3-meshio python3-vtk9
  python3-pydicom python3-nibabel dicom3tools black python3-flake8
  libcgal-demo
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "tactus setup: installing ${#missing[@]} Debian packages: ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if [ ! -f "$BUILD/build.ninja" ]; then
  # shellcheck disable=SC2086
  cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release ${TACTUS_CMAKE_ARGS:-}
fi
cmake --build "$BUILD" -j"$(nproc)"
