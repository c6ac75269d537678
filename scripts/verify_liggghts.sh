#!/usr/bin/env bash
# verify_liggghts.sh: one pile test run by the twin and by LIGGGHTS 3.8 on the same scene, seed
# by seed, both measured by the twin's particle measure (H, D, atan(2H/D)); prints both, their
# means and spreads, and whether the means agree within the seed spread.
#
# The deck is `reposetwin export` (experiments/export/liggghts_deck.hpp says what it carries);
# LIGGGHTS runs it under `mpirun -np NP`. LIGGGHTS' epsd2 has no rolling dashpot, so the twin
# runs with rolling_damping = 0 on every contact of the scene (a --set per contact, printed), the
# same law on both sides. Not CI: it installs the Debian packages liggghts and openmpi-bin if
# they are missing, and a pile of the default scene costs minutes on each side.
#
# With --from-twin-fill, LIGGGHTS starts each seed from the twin's filled sample (the run's
# frames/filled.vtp, `reposetwin export --initial-state`): the fill and the grain sizes are then
# the same in both, and a difference that remains is in the pour's dynamics.
#
# Usage: scripts/verify_liggghts.sh [SCENE] [--seeds 1,2,3] [--np 2] [--out DIR] [--build DIR]
#                                   [--from-twin-fill] [--set key=value ...]
# Default SCENE: data/scenes/paper/table1_s4_dmax8p0_900g_reduced.toml with mu_r 0.4 (the
# issue-37 study's base case). Results: DIR/summary.csv and the table on stdout.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=lib/need.sh
source "${root}/scripts/lib/need.sh"
scene="${root}/data/scenes/paper/table1_s4_dmax8p0_900g_reduced.toml"
seeds=1,2,3
np=2
out=runs/verify_liggghts
build="${root}/build"
sets=()
default_scene=1
from_fill=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --seeds) seeds="$2"; shift 2 ;;
    --np) np="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    --set) sets+=(--set "$2"); shift 2 ;;
    --from-twin-fill) from_fill=1; shift ;;
    -h|--help) sed -n '2,21p' "$0"; exit 0 ;;
    -*) echo "verify_liggghts.sh: unknown option '$1'" >&2; exit 2 ;;
    *) scene="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"; default_scene=0; shift ;;
  esac
done
[[ -f "${scene}" ]] || { echo "verify_liggghts.sh: ${scene}: no such scene file" >&2; exit 2; }
[[ "${seeds}" =~ ^[0-9]+(,[0-9]+)*$ ]] ||
  { echo "verify_liggghts.sh: --seeds must be a list like 1,2,3 (got '${seeds}')" >&2; exit 2; }
[[ "${np}" =~ ^[1-9][0-9]*$ ]] ||
  { echo "verify_liggghts.sh: --np must be a positive integer (got '${np}')" >&2; exit 2; }
if [[ ${default_scene} -eq 1 ]]; then
  sets=(--set contacts.rock-rock.rolling_friction=0.4 --set contacts.rock-plate.rolling_friction=0.4
        "${sets[@]}")
fi
# The same law on both sides: no rolling dashpot on any contact of the scene.
for c in $(grep -oE '^\[contacts\.[A-Za-z0-9_]+-[A-Za-z0-9_]+\]' "${scene}" | tr -d '[]'); do
  sets+=(--set "${c}.rolling_damping=0")
done

need_packages liggghts=liggghts mpirun=openmpi-bin
need_binary "${root}" "${build}"
bin="${build}/apps/reposetwin/reposetwin"
mpi=(mpirun -np "${np}")
[[ "$(id -u)" -eq 0 ]] && mpi+=(--allow-run-as-root)
# Ranks that yield while they wait: busy-polling ranks starve each other on shared cores.
mpi+=(--oversubscribe --mca mpi_yield_when_idle 1)

mkdir -p "${out}/ours" "${out}/liggghts"
echo "scene ${scene}; overrides: ${sets[*]}"
echo "seed,engine,status,H_mm,D_mm,theta_hd_deg,particles,wall_s" > "${out}/summary.csv"
IFS=, read -r -a seed_list <<< "${seeds}"
for s in "${seed_list[@]}"; do
  ours="${out}/ours/seed_${s}"
  if [[ ! -f "${ours}/result.json" ]]; then
    t0=$(date +%s.%N)
    # One thread that sleeps while it waits: on shared cores a spinning second thread
    # starves its partner (bench/compare_liggghts.sh, --wait yield).
    OMP_NUM_THREADS=1 OMP_WAIT_POLICY=passive "${bin}" run "${scene}" --out "${ours}" --set "scene.seed=${s}" "${sets[@]}" --no-images \
      --yes --quiet --force > "${ours}.log" 2>&1 || true
    echo "$(date +%s.%N) - ${t0}" | bc > "${ours}.wall"
  fi
  if [[ ! -f "${ours}/result.json" ]]; then
    echo "verify_liggghts.sh: the twin's run of seed ${s} wrote no result: ${ours}.log" >&2
    exit 1
  fi
  jq -r --arg s "${s}" --arg w "$(cat "${ours}.wall" 2>/dev/null || echo 0)" \
    '. as $r | def mm: if . == null then null else . * 1000 end;
     [$s, "reposetwin", (if $r.no_headline then $r.no_headline.reason else $r.pile.status end),
      ($r.pile.height_m | mm), ($r.pile.base_diameter_m | mm), $r.pile.theta_hd_deg,
      $r.particles.initial, ($w | tonumber)]
     | @csv' "${ours}/result.json" >> "${out}/summary.csv"

  lig="${out}/liggghts/seed_${s}"
  if [[ ! -f "${lig}/final.dump" ]]; then
    initial=()
    if [[ ${from_fill} -eq 1 ]]; then
      [[ -f "${ours}/frames/filled.vtp" ]] || { echo "verify_liggghts.sh: ${ours}/frames/filled.vtp:" \
        "the twin's run wrote no filled state (output.frame_interval_s must be > 0)" >&2; exit 1; }
      initial=(--initial-state "${ours}/frames/filled.vtp")
    fi
    "${bin}" export "${scene}" --out "${lig}" --seed "${s}" "${sets[@]}" "${initial[@]}" --force
    t0=$(date +%s.%N)
    (cd "${lig}" && "${mpi[@]}" liggghts -in in.pile > liggghts.log 2>&1) ||
      { echo "verify_liggghts.sh: LIGGGHTS failed on seed ${s}: ${lig}/liggghts.log" >&2; exit 1; }
    echo "$(date +%s.%N) - ${t0}" | bc > "${lig}.wall"
  fi
  "${bin}" measure-particles "${lig}/final.dump" --scene "${scene}" "${sets[@]}" --json |
    jq -r --arg s "${s}" --arg w "$(cat "${lig}.wall")" \
      '[$s, "liggghts",
        # A clog: the container lifted most grains away, and what fell before it is no pile.
        (if .status == "ok" and .pile_count < 0.9 * .particles then "jam" else .status end),
        (.height_m | if . == null then null else . * 1000 end),
        (.base_diameter_m | if . == null then null else . * 1000 end), .theta_hd_deg,
        .particles, ($w | tonumber)] | @csv' >> "${out}/summary.csv"
done

# The table, the means and spreads, and the verdict: means agree when their difference is
# within twice its standard error from the seed spreads.
# Only settled piles ("ok") enter the means; a jam is printed and counted out.
awk -F, 'NR > 1 { gsub(/"/, ""); e = $2; if ($3 != "ok") { printf "seed %s %-10s %s: no pile\n", $1, e, $3; next } n[e]++; for (k = 4; k <= 6; k++) { s[e, k] += $k; q[e, k] += $k * $k }
               printf "seed %s %-10s %-6s H %6.1f mm  D %6.1f mm  atan(2H/D) %6.2f deg  %s grains  wall %.0f s\n", $1, e, $3, $4, $5, $6, $7, $8 }
  END {
    split("H_mm D_mm theta_deg", name, " ")
    for (k = 4; k <= 6; k++) {
      for (e in n) { m[e] = s[e, k] / n[e]; v[e] = n[e] > 1 ? (q[e, k] - n[e] * m[e] * m[e]) / (n[e] - 1) : 0; if (v[e] < 0) v[e] = 0 }
      se = sqrt(v["reposetwin"] / n["reposetwin"] + v["liggghts"] / n["liggghts"])
      d = m["reposetwin"] - m["liggghts"]
      printf "%-9s reposetwin %7.2f +- %5.2f   liggghts %7.2f +- %5.2f   difference %+6.2f (2 se %.2f): %s\n",
        name[k - 3], m["reposetwin"], sqrt(v["reposetwin"]), m["liggghts"], sqrt(v["liggghts"]), d, 2 * se,
        (d * d <= 4 * se * se ? "agree within the seed spread" : "DIFFER beyond the seed spread")
    }
  }' "${out}/summary.csv"
