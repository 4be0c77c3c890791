#!/usr/bin/env bash
# Installs the Debian 12 packages imm-monoslam needs (only those missing). Needs root for apt-get.
set -euo pipefail
PKGS=(
  build-essential cmake pkg-config ccache
  libmrpt-dev mrpt-apps          # MRPT 2.5 (libraries, SceneViewer3D, RawLogViewer)
  libopencv-dev libeigen3-dev zlib1g-dev
  libceres-dev                   # Ceres Solver 2.1: libs/refine (bundle adjustment, keyframe smoother)
  libgtest-dev libgmock-dev libbenchmark-dev
  libegl1 libegl-mesa0 libgl1-mesa-dri   # offscreen scene snapshots (EGL, no X needed)
  clang libclang-rt-14-dev llvm-14       # fuzz.sh: libFuzzer + sanitizer runtimes, llvm-symbolizer
  opencv-doc                     # its example videos: real video of a hand and of people (tests, real-videos.sh)
  python3 python3-matplotlib     # share/scripts/plot-run.py: the figures of a run from its CSV files
)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
