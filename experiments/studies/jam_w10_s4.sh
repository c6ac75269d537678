#!/usr/bin/env bash
# Issue 37's jam check at the paper's narrow outlet: Table 1 sample 4 (reduced scene, d 5.6-8 mm)
# through a W = 10 mm funnel (W/d_max 1.25; the paper's Fig. 10 funnel jams there), with the
# grains' restitution at 0.3 and mu_r 0.4 (epsd) on rock-rock and rock-plate, seeds 1-3, one
# thread, no photographs. Writes OUT/seed_<n>/ (each run's result.json) and OUT/summary.csv.
#
#   experiments/studies/jam_w10_s4.sh [OUT] [BIN]     (default runs/jam_w10_s4, build's binary)
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${1:-runs/jam_w10_s4}
bin=${2:-$root/build/apps/reposetwin/reposetwin}
mkdir -p "$out"
echo "seed,exit,stop,lodged_particles,particles,wall_s,code_version" > "$out/summary.csv"
for s in 1 2 3; do
  "$bin" run "$root/data/scenes/paper/table1_s4_dmax8p0_900g_reduced.toml" --out "$out/seed_$s" \
    --threads 1 --no-images -q --set scene.seed=$s --set container.bottom_diameter_m=0.01 \
    --set contacts.rock-rock.restitution=0.3 --set contacts.rock-rock.rolling_friction=0.4 \
    --set contacts.rock-plate.rolling_friction=0.4 > /dev/null 2>&1
  rc=$?
  jq -r --arg s "$s" --arg rc "$rc" \
    '[$s, $rc, .stop.reason, .pile.lodged_particles, .particles.initial,
      .performance.wall_s, .provenance.code_version] | @csv' "$out/seed_$s/result.json" \
    >> "$out/summary.csv"
done
cat "$out/summary.csv"
