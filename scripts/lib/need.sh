# Sourced by the scripts that need Debian tools or the twin's binary (not run alone).
#
# need_packages CMD=PACKAGE ...: installs, from Debian with --no-install-recommends, the package of
#   each command not on the PATH (never the recommends: liggghts recommends paraview, which
#   removes the VTK headers the twin builds against).
# need_binary ROOT BUILD: builds the twin's binary in BUILD when it is not there yet.
need_packages() {
  local missing=() pair
  for pair in "$@"; do
    command -v "${pair%%=*}" >/dev/null || missing+=("${pair#*=}")
  done
  [[ ${#missing[@]} -eq 0 ]] && return 0
  echo "installing ${missing[*]} (Debian packages, --no-install-recommends) ..." >&2
  local sudo_cmd=()
  [[ "$(id -u)" -ne 0 ]] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >&2
}

need_binary() {
  local root="$1" build="$2"
  if [[ ! -x "${build}/apps/reposetwin/reposetwin" ]]; then
    cmake -S "${root}" -B "${build}" >/dev/null && cmake --build "${build}" -j2 --target reposetwin
  fi
}
