#!/usr/bin/env bash
# The closed loop's validation on twin-made lab data with one hidden effect each: makes every
# case's synthetic dataset (reposetwin loop-synth), runs the loop on it (reposetwin loop) and
# writes OUT/summary.csv and OUT/summary.json: per case the effect hidden, the effect named,
# the fitted value, the RMSE before and after, the cut and whether the case's expectation held.
#
#   experiments/loop_validation/run.sh [--out DIR] [--force] [--workers N] [CASE ...]
#
# CASE names a row of the table below (default: all). Resumable: a case whose loop.json exists
# is kept (--force recomputes it; the simulation cache in DIR/cache is kept either way, so a
# killed run resumes where it stopped). REPOSETWIN names the binary (default: build/...).
#
# The loop's settings are those of the end-to-end tests (tests/experiments/loop/loop_synth_test.cpp):
# mu_r grid 0.1/0.2/0.35 (0.1/0.25/0.5 for the size design), three seeds (six where a case says so), 960x720 photos with
# two side views in the twin's own framing, one effect at most, a calibrated mu_r on the grid's
# bound traced with the correction held inside the grid (docs/loop.md, "Synthetic end-to-end
# tests", says why).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${REPOSETWIN:-$root/build/apps/reposetwin/reposetwin}
out=runs/loop_validation
force=0
workers=2
only=()
while (($#)); do
  case $1 in
    --out) out=$2; shift 2 ;;
    --force) force=1; shift ;;
    --workers) workers=$2; shift 2 ;;
    -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
    -*) echo "run.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) only+=("$1"); shift ;;
  esac
done
[[ -x $bin ]] || { echo "run.sh: no reposetwin binary at $bin (build first, or set REPOSETWIN)" >&2; exit 2; }
command -v jq >/dev/null || { echo "run.sh: jq is needed (scripts/install_deps.sh installs it)" >&2; exit 2; }

# name | design (data/loop/) | mu_r grid | effect expected (none: nothing named; refused: the
# loop must refuse the data before it simulates) | side of its off value the fit must land
# (below/above/-) | least RMSE cut on the calibration tests | candidates (empty: the loop's
# default, every registry effect but the opt-in grain_shape) | the loop's seeds (empty:
# 1001,1002,1003; as many as the design's repeats where a case needs the lower noise) | mu_r's
# declared range LO,HI (empty: none), which the fitted mu_r must then lie inside; the grid then
# reaches the range's end, so that mu_r alone needing more than the range is seen as such.
# The least cut is 70% wherever an effect is hidden: the refit's RMSE cannot fall below one
# residual's noise, the seed spread times sqrt(1/n_lab + 1/n_twin) (1.23 deg with three piles a
# side), so a hidden effect weaker than about three times that cannot show a 70% cut, and such a
# design does not test the loop. The cohesion, size and shape designs therefore repeat each test
# on six piles (floor 0.87 deg at the shape designs' spread). The shape designs declare mu_r's
# range for rock, 0.02-0.4, as a user should: rods at mu_r 0.25 stand like spheres at 0.5, so
# without it mu_r alone climbs the grid and the fingerprints are taken at the wrong end of it.
shape_candidates=grain_shape,plate_friction,lift_speed,cohesion,camera_height
six=1001,1002,1003,1004,1005,1006
cases=(
  "plate|synth_plate.toml|0.1,0.2,0.35|plate_friction|below|0.70|||"
  "lift|synth_lift.toml|0.1,0.2,0.35|lift_speed|above|0.70|||"
  "cohesion|synth_cohesion.toml|0.1,0.2,0.35|cohesion|above|0.70||$six|"
  "null|synth_null.toml|0.1,0.2,0.35|none|-|0|||"
  "camera|synth_camera.toml|0.1,0.2,0.35|refused|-|0|||"
  "rolling_size|synth_size.toml|0.1,0.25,0.5|rolling_size|above|0.70||$six|"
  "shape_repeats|synth_shape_repeats.toml|0.1,0.25,0.4|grain_shape|above|0.70|$shape_candidates|$six|0.02,0.4"
  "shape_low_mu|synth_shape_low_mu.toml|0.1,0.2,0.4|grain_shape|above|0.70|$shape_candidates|$six|0.02,0.4"
)

mkdir -p "$out"
known=" $(printf '%s\n' "${cases[@]}" | cut -d'|' -f1 | tr '\n' ' ')"
for c in "${only[@]}"; do
  [[ $known == *" $c "* ]] || { echo "run.sh: unknown case '$c' (cases:$known)" >&2; exit 2; }
done

# A loop that refuses its data (exit 2: bad input, e.g. photos that contradict their declared
# camera) leaves DIR/CASE/refused.txt with its message instead of a loop.json.
run_case() {
  local name=$1 design=$2 grid=$3 candidates=$4 seeds=${5:-1001,1002,1003} range=$6
  local dir=$out/$name
  if [[ ( -f $dir/loop/loop.json || -f $dir/refused.txt ) && $force == 0 ]]; then
    echo "[validation] $name: finished earlier (kept; --force recomputes)"
    return
  fi
  echo "[validation] $name: dataset from data/loop/$design"
  "$bin" loop-synth "$root/data/loop/$design" --out "$dir/data" --cache "$out/cache" \
    --truth "$dir/truth.json" --workers "$workers" >/dev/null
  echo "[validation] $name: loop"
  rm -f "$dir/refused.txt"
  local rc=0
  "$bin" loop "$dir/data/measured.csv" --out "$dir/loop" --cache "$out/cache" \
    --mu-grid "$grid" --seeds "$seeds" --width 960 --height 720 --views 2 --own-cameras \
    ${candidates:+--candidates "$candidates"} \
    ${range:+--mu-range "$range" --mu-range-reason "rock in our convention (the case's premise)"} \
    --max-effects 1 --at-bound trace --grid-extensions 0 --workers "$workers" --force --quiet \
    >/dev/null 2>"$dir/loop_stderr.txt" || rc=$?
  if ((rc == 2)); then
    mv "$dir/loop_stderr.txt" "$dir/refused.txt"
    echo "[validation] $name: the loop refused the data: $(head -c 300 "$dir/refused.txt")"
  elif ((rc != 0)); then
    echo "[validation] $name: the loop failed (exit $rc): $(tail -c 300 "$dir/loop_stderr.txt")" >&2
    exit 1
  fi
}

rows=()
for row in "${cases[@]}"; do
  IFS='|' read -r name design grid want side cut candidates seeds range <<<"$row"
  if ((${#only[@]})) && [[ " ${only[*]} " != *" $name "* ]]; then continue; fi
  run_case "$name" "$design" "$grid" "$candidates" "$seeds" "$range"
  rows+=("$row")
done

# One line per case from its loop.json; "held" applies the case's expectation. angle_only and
# joint give the first iteration's two best candidates by the angle alone (leave-one-out RMSE)
# and by the joint fit of angle, H and D (chi^2 per channel), to show where they part.
summary=$out/summary.json
for row in "${rows[@]}"; do
  IFS='|' read -r name design grid want side cut _ _ range <<<"$row"
  if [[ -f $out/$name/refused.txt ]]; then
    jq -n -c --arg name "$name" --arg design "data/loop/$design" --arg grid "$grid" \
      --arg want "$want" --rawfile why "$out/$name/refused.txt" \
      '{case: $name, design: $design, mu_grid: $grid, expected: $want, named: null,
        verdict: "refused", refused: ($why | rtrimstr("\n")), held: ($want == "refused")}'
    continue
  fi
  jq -c --arg name "$name" --arg design "data/loop/$design" --arg grid "$grid" \
    --arg want "$want" --arg side "$side" --argjson cut "$cut" --arg range "$range" \
    --slurpfile truth "$out/$name/truth.json" '
    .summary as $s | (.final.effects[0] // null) as $e | $truth[0] as $t |
    ($e.joint_region // null) as $g |
    (if $range == "" then null else ($range | split(",") | map(tonumber)) end) as $r |
    {case: $name, design: $design, mu_grid: $grid, expected: $want,
     named: $s.chosen, verdict: $s.verdict,
     hidden_mu_r: $t.mu_r, hidden_value: ($t.hidden[0].value // null),
     value: ($e.value // null), value_se: ($e.value_se // null), off: ($e.off // null),
     mu_r: .final.mu_r, mu_r_range_declared: $r,
     region_value: ($g.value_range // null), region_mu_r: ($g.mu_r_range // null),
     region_correlation: ($g.correlation // null), region_separated: ($g.separated // null),
     hidden_in_region: (if $g == null or $t.hidden[0] == null then null else
       ($t.hidden[0].value >= $g.value_range[0] and $t.hidden[0].value <= $g.value_range[1] and
        $t.mu_r >= $g.mu_r_range[0] and $t.mu_r <= $g.mu_r_range[1]) end),
     rmse_calibrate_before_deg: $s.rmse_calibrate_before_deg,
     rmse_calibrate_after_deg: $s.rmse_calibrate_after_deg,
     rmse_validate_before_deg: $s.rmse_validate_before_deg,
     rmse_validate_after_deg: $s.rmse_validate_after_deg,
     cut: $s.reduction, least_cut: $cut,
     pile_runs: .simulations.pile_runs_started, wall_s: .simulations.wall_s,
     angle_only: [.iterations[0].candidates // [] | sort_by(.loo_rmse_deg)[:2][] |
                  {name, loo_rmse_deg, t, accepted}],
     joint: [.iterations[0].joint // [] | sort_by(.chi2)[:2][] |
             {name, chi2, chi2_by_channel, values}],
     code_version: .provenance.code_version} |
    .held = (if $want == "none" then .named == null
             else (.named == $want and .cut >= $cut and
                   (if $side == "below" then .value < .off else .value > .off end) and
                   ($r == null or (.mu_r >= $r[0] and .mu_r <= $r[1]))) end)' \
    "$out/$name/loop/loop.json"
done | jq -s '.' >"$summary.tmp" && mv "$summary.tmp" "$summary"
jq -r '(["case","expected","named","value","value_se","mu_r","rmse_cal_before_deg",
         "rmse_cal_after_deg","rmse_val_before_deg","rmse_val_after_deg","cut","least_cut",
         "hidden_value","region_value_lo","region_value_hi","hidden_mu_r","region_mu_r_lo",
       "region_mu_r_hi","hidden_in_region","held","code_version"] | @csv),
       (.[] | [.case,.expected,(.named // .verdict),.value,.value_se,.mu_r,.rmse_calibrate_before_deg,
               .rmse_calibrate_after_deg,.rmse_validate_before_deg,.rmse_validate_after_deg,
               .cut,.least_cut,.hidden_value,.region_value[0],.region_value[1],.hidden_mu_r,
               .region_mu_r[0],.region_mu_r[1],.hidden_in_region,.held,.code_version] | @csv)' \
  "$summary" >"$out/summary.csv.tmp"
mv "$out/summary.csv.tmp" "$out/summary.csv"
column -s, -t <"$out/summary.csv"
jq -e 'all(.held)' "$summary" >/dev/null || { echo "[validation] some expectations did not hold" >&2; exit 1; }
