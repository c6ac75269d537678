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

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }

missing=()
for p in "${PACKAGES[@]}"; do
  if ! installed "$p"; then
    missing+=("$p")
  fi
done

# ParaView's Python (python3-paraview, recommended by paraview, itself recommended by liggghts)
# conflicts with python3-vtk9, on which libvtk9-dev depends: installing LIGGGHTS or ParaView with
# their recommended packages removes the VTK headers. Installing them back would remove ParaView's
# Python in turn, so this script does not do it unasked: it says what happened and what to run.
if ! installed libvtk9-dev && installed python3-paraview; then
  cat >&2 <<'EOF'
install_deps: the VTK headers are missing (libvtk9-dev is not installed) and python3-paraview is.
  Debian's python3-paraview (ParaView's Python, for pvpython) conflicts with python3-vtk9, on which
  libvtk9-dev depends; apt removed both when ParaView came in with recommended packages (as
  `apt-get install liggghts` pulls in paraview and python3-paraview). The twin needs libvtk9-dev
  to build.
  To build the twin again (this removes python3-paraview; ParaView's viewer and LIGGGHTS stay):
    sudo apt-get install --no-install-recommends libvtk9-dev python3-vtk9
  Install LIGGGHTS and ParaView without their recommended packages from then on:
    sudo apt-get install --no-install-recommends liggghts paraview
EOF
  exit 1
fi

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "install_deps: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
