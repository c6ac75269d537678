#!/usr/bin/env bash
# compare_yade.sh: bench_clumps' settled bed of tetrahedral four-sphere clumps run by ReposeTwin's
# engine and by Yade (Debian's package) side by side on one core; prints body-steps/s and
# component-steps/s of both and the ratio ours / Yade.
#
# bench_clumps constructs and settles the clump bed (or reads it with --beds), writes it for Yade
# (--write-yade: every clump's component spheres in world coordinates, its velocity, angular
# velocity, mass and principal moments, and a script with the same plate and container, Hertz-
# Mindlin contact (Law2_ScGeom_MindlinPhys_Mindlin), E, nu, e, mu_s, dt and Verlet distance),
# then times its own run on one thread; this script then times Yade on that input with one
# thread (yade -j1). Only the timed steps count on both sides (ours: the steps after the settle;
# Yade: O.run(STEPS) after one untimed step that builds its collider and contacts). Both are
# also given in CPU seconds (process CPU time of the timed steps), which a shared machine's load
# does not inflate as much as wall time. The physics is close, not identical: bench/README.md
# lists the differences (rolling resistance above all).
#
# Usage: bench/compare_yade.sh [--quick | --issue] [--clumps N] [--steps N] [--settle N]
#                              [--relax N] [--container-mm R] [--seed S] [--beds PREFIX]
#                              [--build DIR] [--work DIR]
# --issue is bench_clumps' issue bed: 50,000 clumps in a 120 mm container (bench/README.md).
# This is a benchmark, not CI: it installs the Debian package yade if it is missing.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "${here}/.." && pwd)"
build=/tmp/build-bench
work=/tmp/reposetwin-yade
bench_args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --quick|--issue) bench_args+=("$1"); shift ;;
    --clumps|--steps|--settle|--relax|--seed|--beds|--container-mm)
      [[ $# -ge 2 ]] || { echo "compare_yade.sh: $1 needs a value" >&2; exit 2; }
      bench_args+=("$1" "$2"); shift 2 ;;
    --build|--work)
      [[ $# -ge 2 ]] || { echo "compare_yade.sh: $1 needs a value" >&2; exit 2; }
      [[ "$1" == --build ]] && build="$2" || work="$2"; shift 2 ;;
    -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
    *) echo "compare_yade.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done

# 1. Yade, from Debian. --no-install-recommends keeps its recommended GUI stack out.
if ! command -v yade > /dev/null; then
  echo "installing yade (Debian package) ..." >&2
  sudo_cmd=()
  [[ "$(id -u)" -ne 0 ]] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get install -y --no-install-recommends yade >&2
fi
yade_version="$(dpkg-query -W -f '${Version}' yade 2> /dev/null || echo unknown)"

# 2. Our side: build, construct + settle (or read) the bed, write Yade's input, time our run on
#    one thread.
[[ -d "${build}" ]] || cmake -S "${root}" -B "${build}" -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build "${build}" --target bench_clumps -j2 > /dev/null
mkdir -p "${work}"
echo "commit $(git -C "${root}" rev-parse --short HEAD 2> /dev/null || echo unknown), yade ${yade_version}"
echo "load before: $(cat /proc/loadavg)"
OMP_NUM_THREADS=1 "${build}/bench/bench_clumps" "${bench_args[@]}" --no-spheres --threads 1 \
  --settle-threads 1 --write-yade "${work}" | tee "${work}/bench_clumps.log"
field() {  # field LINE NAME -> value of NAME=... in LINE
  tr ' ' '\n' <<< "$1" | sed -n "s/^$2=//p"
}
result="$(grep '^RESULT' "${work}/bench_clumps.log")"
timing="$(grep '^TIMING threads=1 ' "${work}/bench_clumps.log")"
clumps="$(field "${result}" clumps)"
components="$(field "${result}" components)"
steps="$(field "${result}" steps)"
our_wall="$(field "${timing}" clump_seconds)"
our_cpu="$(field "${timing}" clump_cpu_seconds)"

# 3. Yade on the same bed, one thread.
echo "Yade, 1 thread: load $(cat /proc/loadavg)"
(cd "${work}" && OMP_NUM_THREADS=1 yade -j1 -n -x run.py > yade.log 2>&1) ||
  { echo "Yade failed, see ${work}/yade.log" >&2; tail -20 "${work}/yade.log" >&2; exit 1; }
yline="$(grep '^YADE ' "${work}/yade.log" | tail -1)"
echo "  ${yline}"
[[ "$(field "${yline}" clumps)" == "${clumps}" && "$(field "${yline}" steps)" == "${steps}" ]] ||
  { echo "compare_yade.sh: Yade ran another bed or step count: ${yline}" >&2; exit 1; }
yade_wall="$(field "${yline}" seconds)"
yade_cpu="$(field "${yline}" cpu_seconds)"
echo "load after: $(cat /proc/loadavg)"

# 4. The table: per core (one core each).
echo
printf '%-9s %-18s %-18s %-18s %-18s %s\n' time "ours [body-st/s]" "Yade [body-st/s]" \
  "ours [comp-st/s]" "Yade [comp-st/s]" "ours/Yade"
summary="RESULT_COMPARE clumps=${clumps} components=${components} steps=${steps} yade=${yade_version}"
for kind in wall cpu; do
  if [[ "${kind}" == wall ]]; then a="${our_wall}"; b="${yade_wall}"; else a="${our_cpu}"; b="${yade_cpu}"; fi
  read -r ob yb oc yc r < <(awk -v n="${clumps}" -v m="${components}" -v s="${steps}" -v a="${a}" \
    -v b="${b}" 'BEGIN { printf "%.4g %.4g %.4g %.4g %.3f\n", n*s/a, n*s/b, m*s/a, m*s/b, b/a }')
  printf '%-9s %-18s %-18s %-18s %-18s %s\n' "${kind}" "${ob}" "${yb}" "${oc}" "${yc}" "${r}"
  summary+=" ours_body_steps_${kind}=${ob} yade_body_steps_${kind}=${yb} ratio_${kind}=${r}"
done
echo "${summary}"
