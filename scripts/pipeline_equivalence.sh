#!/usr/bin/env bash
# Runs a small campaign, a small calibration and the tiny loop with one reposetwin binary, so two
# builds (before and after a change of the pipeline) can be compared result by result:
#
#   scripts/pipeline_equivalence.sh run BIN OUT       # OUT/{campaign,calibration,loop}/...
#   scripts/pipeline_equivalence.sh compare OUT_A OUT_B
#
# All three run on data/loop/tiny_scene.toml (about a hundred spheres; the whole set is a few
# minutes on 2 cores). `compare` diffs every JSON result with the fields that name how and where a
# result was made removed (provenance, versions, cache keys and folders, timings), since those
# differ between builds by design; anything else that differs is printed and the exit code is 1.
set -euo pipefail

here="$(cd "$(dirname "$0")/.." && pwd)"
tiny="$here/data/loop/tiny_scene.toml"

run() {
  local bin="$1" out="$2"
  mkdir -p "$out"
  out="$(cd "$out" && pwd)"
  cat >"$out/campaign.toml" <<EOF
name = "equivalence_campaign"
description = "two mu_r values x two seeds of the tiny scene"
scene = "$tiny"
seeds = [1, 2]

[sweep]
key = "contacts.rock-rock.rolling_friction"
values = [0.1, 0.3]
name = "mu_r"
EOF
  cat >"$out/calibration.toml" <<EOF
name = "equivalence_calibration"
description = "mu_r of the tiny scene for a 25 deg pile, one prediction"
scene = "$tiny"
seeds = [1]

[calibration]
key = ["contacts.rock-rock.rolling_friction", "contacts.rock-plate.rolling_friction"]
target_deg = 25.0
target_sd_deg = 0.5
mu_r_range = [0.05, 0.5]
seeds_per_point = 1
max_simulations = 4

[[predict]]
name = "heavier"
scene = "$tiny"
measured_deg = 26.0
overrides = { "sample.mass_kg" = 0.008 }
EOF
  local t0=$SECONDS
  "$bin" campaign "$out/campaign.toml" --out "$out/campaign" --views 2 >"$out/campaign.log" 2>&1 ||
    echo "campaign exit $?" >>"$out/campaign.log"
  local t1=$SECONDS
  "$bin" calibrate "$out/calibration.toml" --out "$out/calibration" --views 2 \
    >"$out/calibration.log" 2>&1 || echo "calibrate exit $?" >>"$out/calibration.log"
  local t2=$SECONDS
  "$bin" loop "$here/data/loop/example.csv" --out "$out/loop" --mu-grid 0.1,0.3 --seeds 1001,1002 \
    --max-effects 1 --candidates plate_friction,lift_speed --quiet >"$out/loop.log" 2>&1 ||
    echo "loop exit $?" >>"$out/loop.log"
  local t3=$SECONDS
  echo "campaign $((t1 - t0)) s, calibration $((t2 - t1)) s, loop $((t3 - t2)) s" | tee "$out/times.txt"
}

# A JSON file with how and where it was made removed, keys sorted, its output folder as OUT.
strip() {
  sed "s#$2#OUT#g" "$1" | jq -S 'walk(if type == "object" then
      with_entries(select(.key | test("^(provenance|version|code_version|engine_version|imaging_version|git_.*|build.*|host.*|hostname|created.*|started.*|finished.*|date|time_utc|utc|timestamp|wall.*|elapsed.*|.*_seconds|.*_s_wall|performance|cache|cache_dir|sim_dir|image_dir|dir|run_dir|variant|command|cwd|file|path|out|out_dir|scene_path|images|photo|overlay|lab_photo|twin_photo|ranks|workers|threads|updated|source|attempts|timing|started_utc|pid)$") | not))
    else . end)'
}

compare() {
  local a b bad=0 n=0
  a="$(cd "$1" && pwd)"
  b="$(cd "$2" && pwd)"
  while IFS= read -r rel; do
    n=$((n + 1))
    if [[ ! -f "$b/$rel" ]]; then
      echo "only in $a: $rel"
      bad=1
      continue
    fi
    if ! diff <(strip "$a/$rel" "$a") <(strip "$b/$rel" "$b") >/tmp/pipeline_equivalence.diff; then
      echo "differs: $rel"
      head -40 /tmp/pipeline_equivalence.diff
      bad=1
    fi
  done < <(cd "$a" && find campaign calibration loop -name '*.json' -not -path '*/cache/*' \
             -not -path '*/run/*' -not -path '*/images/*' -not -name 'started.json' | sort)
  echo "$n JSON files compared: $([[ $bad == 0 ]] && echo identical || echo DIFFERENT) apart from provenance"
  return $bad
}

case "${1:-}" in
  run) run "$2" "$3" ;;
  compare) compare "$2" "$3" ;;
  *) echo "usage: $0 run BIN OUT | compare OUT_A OUT_B" >&2; exit 2 ;;
esac
