#!/usr/bin/env bash
# Installs ReposeTwin's build and test dependencies from Debian's packages, only those missing.
# Safe to run repeatedly; needs root (or sudo) only when something is missing.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev            # vector math (sim/)
  libosmesa6-dev           # offscreen OpenGL (render/)
  libopencv-dev            # image measurement (vision/): core, imgproc, imgcodecs
  libvtk9-dev              # VTK XML .vtp/.pvd output (IOXML only)
  libtomlplusplus-dev      # scene and campaign files
  libcli11-dev             # command line
  nlohmann-json3-dev       # result files
  libkainjow-mustache-dev  # HTML templates of the reports (header-only)
  libcsv-dev               # CSV reader (the paper's tables, measured data)
  libssl-dev               # SHA-256 (libcrypto) of the pile service's store keys
  libgtest-dev             # tests
  gnuplot-nox              # report plots
  libopenmpi-dev openmpi-bin  # optional campaign spreading under mpirun
  jq                       # experiments/loop_validation/run.sh: its summary from loop.json
)
# scripts/fuzz.sh only: clang with libFuzzer and the sanitizers' runtime.
if [ "${1:-}" = "--fuzz" ]; then
  PACKAGES+=(clang libclang-rt-dev)
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "install_deps: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
