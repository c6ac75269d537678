#!/usr/bin/env bash
# compare_liggghts.sh: the standard heap of bench_sim run by ReposeTwin's engine and by
# LIGGGHTS 3.8 side by side, on 1 and 2 cores; prints particle-steps per second per core of both
# and the ratio ours / LIGGGHTS.
#
# bench_sim constructs and settles the heap, writes it (positions, sizes, velocities) with the
# matching LIGGGHTS input (same Hertz-Mindlin + rolling law, E, nu, e, mu_s, mu_r, dt, skin and
# number of steps), then times its own run; this script then times LIGGGHTS on that input with
# 1 and 2 MPI ranks. Only the timed run counts on both sides (LIGGGHTS's "Loop time").
# One-core figures are also given in CPU seconds (ours: the process CPU time of the timed steps;
# LIGGGHTS: CPU time of "run N" minus that of "run 0" on the same data), which a shared machine's
# load does not inflate; two-core figures exist only as wall time.
#
# Waiting (--wait): "spin" (the default, for an idle machine) leaves both sides as they come:
# libgomp's default policy (a waiting thread spins a while, then sleeps) and Open MPI's busy
# polling. "yield" (for a shared machine) makes waiting threads sleep (OMP_WAIT_POLICY=passive)
# and ranks yield (mpi_yield_when_idle): there a spinning thread or rank keeps the core its
# partner needs (our 2-thread run was up to 100x slower), but on an idle machine each of our
# three parallel phases per step then waits ~0.1 ms for a sleeping thread to wake (bench/README.md,
# session 9), which MPI's polling ranks never pay.
#
# Usage: bench/compare_liggghts.sh [--quick] [--particles N] [--steps N] [--rolling epsd|cdt]
#                                  [--cores 1,2] [--wait spin|yield] [--build DIR] [--work DIR]
# This is a benchmark, not CI: it installs the Debian package liggghts if it is missing.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "${here}/.." && pwd)"
build=/tmp/build-bench
work=/tmp/reposetwin-liggghts
cores=1,2
wait=spin
bench_args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --quick) bench_args+=(--quick); shift ;;
    --particles|--steps|--rolling|--settle|--relax|--settle-threads|--seed)
      [[ $# -ge 2 ]] || { echo "compare_liggghts.sh: $1 needs a value" >&2; exit 2; }
      bench_args+=("$1" "$2"); shift 2 ;;
    --cores) cores="$2"; shift 2 ;;
    --wait) wait="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    --work) work="$2"; shift 2 ;;
    -h|--help) sed -n '2,24p' "$0"; exit 0 ;;
    *) echo "compare_liggghts.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
if ! [[ "${cores}" =~ ^[0-9]+(,[0-9]+)*$ ]]; then
  echo "compare_liggghts.sh: --cores must be a list like 1,2 (got '${cores}')" >&2
  exit 2
fi
if [[ "${wait}" != spin && "${wait}" != yield ]]; then
  echo "compare_liggghts.sh: --wait must be spin or yield (got '${wait}')" >&2
  exit 2
fi

# 1. LIGGGHTS. --no-install-recommends matters: its recommended paraview package removes
#    libvtk9-dev, which this project builds against.
if ! command -v liggghts > /dev/null; then
  echo "installing liggghts (Debian package) ..." >&2
  sudo_cmd=()
  [[ "$(id -u)" -ne 0 ]] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get install -y --no-install-recommends liggghts >&2
fi
mpirun_args=()
[[ "$(id -u)" -eq 0 ]] && mpirun_args+=(--allow-run-as-root)
mpirun_args+=(--oversubscribe)
# How waiting threads and ranks wait, the same on both sides (--wait, above).
if [[ "${wait}" == yield ]]; then
  export OMP_WAIT_POLICY=passive
  mpirun_args+=(--mca mpi_yield_when_idle 1)
else
  unset OMP_WAIT_POLICY
fi
echo "wait ${wait}: OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-(libgomp default)}; mpirun ${mpirun_args[*]}"

# 2. Our side: build, construct + settle the heap, write the LIGGGHTS input, time our run.
[[ -d "${build}" ]] || cmake -S "${root}" -B "${build}" > /dev/null
cmake --build "${build}" --target bench_sim -j2 > /dev/null
mkdir -p "${work}"
echo "load before: $(cat /proc/loadavg)"
"${build}/bench/bench_sim" "${bench_args[@]}" --threads "${cores}" --write-liggghts "${work}" \
  | tee "${work}/bench_sim.log"
ours="$(grep '^RESULT' "${work}/bench_sim.log")"
field() {  # field NAME -> value of NAME=... in the RESULT line
  tr ' ' '\n' <<< "${ours}" | sed -n "s/^$1=//p"
}
particles="$(field particles)"
steps="$(field steps)"

# 3. LIGGGHTS on the identical scene, 1..n ranks; plus a "run 0" for the CPU-time baseline.
cd "${work}"
sed "s/^run .*/run 0/" in.heap > in.heap0
lig_cpu() {  # lig_cpu NP INPUT LOG -> prints "user+sys seconds" of the whole mpirun
  local t0 t1 me="${BASHPID}"
  t0="$(awk '{print $14 + $15 + $16 + $17}' "/proc/${me}/stat")"
  mpirun "${mpirun_args[@]}" -np "$1" liggghts -in "$2" -log "$3" > "$3.out" 2>&1 ||
    { echo "LIGGGHTS failed, see ${work}/$3.out" >&2; tail -5 "$3.out" >&2; exit 1; }
  t1="$(awk '{print $14 + $15 + $16 + $17}' "/proc/${me}/stat")"
  echo "$(( t1 - t0 ))"
}
clk_tck="$(getconf CLK_TCK)"
declare -A lig_wall lig_cpu_run
IFS=',' read -r -a core_list <<< "${cores}"
for np in "${core_list[@]}"; do
  echo "LIGGGHTS, ${np} rank(s): load $(cat /proc/loadavg)"
  ticks="$(lig_cpu "${np}" in.heap "log.np${np}")"
  loop="$(grep '^Loop time' "log.np${np}" | tail -1)"
  echo "  ${loop}"
  lig_wall[${np}]="$(awk '{print $4}' <<< "${loop}")"
  if [[ "${np}" -eq 1 ]]; then
    ticks0="$(lig_cpu 1 in.heap0 log.run0)"
    lig_cpu_run[1]="$(awk -v a="${ticks}" -v b="${ticks0}" -v h="${clk_tck}" \
      'BEGIN { printf "%.4f", (a - b) / h }')"
    echo "  CPU: run ${steps} $(awk -v a="${ticks}" -v h="${clk_tck}" 'BEGIN{print a/h}') s," \
         "run 0 $(awk -v a="${ticks0}" -v h="${clk_tck}" 'BEGIN{print a/h}') s"
  fi
done
echo "load after: $(cat /proc/loadavg)"

# 4. The table.
echo
printf '%-6s %-26s %-26s %s\n' cores "ours [particle-steps/s/core]" \
  "LIGGGHTS [particle-steps/s/core]" "ours/LIGGGHTS"
summary="RESULT_COMPARE particles=${particles} steps=${steps}"
for np in "${core_list[@]}"; do
  our_wall="$(field "seconds_${np}t")"
  read -r o l r < <(awk -v n="${particles}" -v s="${steps}" -v c="${np}" -v a="${our_wall}" \
    -v b="${lig_wall[${np}]}" 'BEGIN { o = n*s/a/c; l = n*s/b/c; printf "%.4g %.4g %.3f\n", o, l, o/l }')
  printf '%-6s %-26s %-26s %s\n' "${np}" "${o}" "${l}" "${r}  (wall)"
  summary+=" ours_per_core_${np}c=${o} liggghts_per_core_${np}c=${l} ratio_${np}c=${r}"
  if [[ "${np}" -eq 1 ]]; then
    our_cpu="$(field "cpu_seconds_1t")"
    read -r o l r < <(awk -v n="${particles}" -v s="${steps}" -v a="${our_cpu}" \
      -v b="${lig_cpu_run[1]}" 'BEGIN { o = n*s/a; l = n*s/b; printf "%.4g %.4g %.3f\n", o, l, o/l }')
    printf '%-6s %-26s %-26s %s\n' "1" "${o}" "${l}" "${r}  (CPU time)"
    summary+=" ours_cpu_1c=${o} liggghts_cpu_1c=${l} ratio_cpu_1c=${r}"
  fi
done
echo "${summary}"
