#!/bin/bash
# The per-case table of a shape study (mean +- sd over the seeds that formed a pile; jams =
# clogged seeds): experiments/studies/study_table.sh CAMPAIGN_OUT_DIR
cd "$1"
printf "| case | seeds done | atan(2H/D) [deg] | flank [deg] | crest [mm] | jams | grains (bodies) | components | wall per run [s] |\n|---|---|---|---|---|---|---|---|---|\n"
for c in $(jq -r "[.runs[].case] | unique_by(.) | .[]" campaign.json); do
  [ -d cases/$c ] || continue
  files=$(ls cases/$c/seed_*/result.json 2>/dev/null) || continue
  [ -n "$files" ] || continue
  for f in $files; do m=$(dirname $f)/run/images/measurement.json
    [ -f $m ] || m=/dev/null
    jq -c --slurpfile m $m '{a:.result.headline_angle_deg, f:.result.image.flank_deg, c:(if ($m|length)>0 then $m[0].crest_width_m*1000 else null end), st:.result.pile.status, stop:.result.stop.reason, n:.result.particles.initial, comp:(.result.shape.components_initial // .result.particles.initial), w:.result.performance.wall_s}' $f
  done | jq -s -r --arg c "$c" '
    def ms(x): map(select(.st=="ok")) | if length==0 then "-" else (map(x)|add/length) as $m | (if length>1 then (map((x-$m)*(x-$m))|add/(length-1)|sqrt) else 0 end) as $s | "\($m*10|round/10) ± \($s*10|round/10)" end;
    "| \($c) | \(length) | \(ms(.a)) | \(ms(.f)) | \(ms(.c)) | \(map(select(.st!="ok"))|length)/\(length) | \(map(.n)|add/length|round) | \(map(.comp)|add/length|round) | \(map(.w)|add/length|round) |"'
done
