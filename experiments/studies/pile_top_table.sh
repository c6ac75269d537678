#!/bin/bash
# The pile-top study's tables and plot from a campaign folder (experiments/studies/pile_top_s4.toml):
#   experiments/studies/pile_top_table.sh CAMPAIGN_OUT_DIR RESULTS_DIR
# writes RESULTS_DIR/runs.csv (one row per finished run, with its provenance), table.md (per case:
# mean +- sd over the seeds that formed a pile; jams = seeds whose outlet clogged or formed no
# pile; a run stopped by its settle time limit is counted apart, as "unsettled", and left out of
# the means, since the twin gives it no headline), cases.dat and crest_angle.png (photo atan(2H/D) and crest width per case, +- sd).
# A case's factor is its name up to the first '_' (base, pour, size, psd, blocky).
set -euo pipefail
src=$(cd "$1" && pwd)
mkdir -p "$2"
out=$(cd "$2" && pwd)

rows() {
  for f in "$src"/cases/*/seed_*/result.json; do
    [ -f "$f" ] || continue
    m=$(dirname "$f")/run/images/measurement.json
    [ -f "$m" ] || m=/dev/null
    jq -c --slurpfile m "$m" --arg case "$(basename "$(dirname "$(dirname "$f")")")" '
      .result as $r | ($m[0] // {}) as $mm |
      {case: $case, seed: $r.provenance.seed, status: $r.pile.status, stop: $r.stop.reason,
       angle: $r.headline_angle_deg, angle_sd: $r.headline_angle_sd_deg,
       h_mm: (if $r.headline_height_m then $r.headline_height_m * 1000 else null end),
       d_mm: (if $r.headline_diameter_m then $r.headline_diameter_m * 1000 else null end),
       flank: $r.image.flank_deg,
       crest_mm: (if $mm.crest_width_m then $mm.crest_width_m * 1000 else null end),
       bodies: ($r.shape.bodies_initial // $r.particles.initial),
       components: ($r.shape.components_initial // $r.particles.initial),
       grain: ($r.shape.shapes[0].name // "sphere"),
       not_simulated: $r.psd_fines_fraction, cpu_s: $r.performance.cpu_s,
       wall_s: $r.performance.wall_s, dt_s: $r.provenance.time_step_s,
       e_soft_pa: $r.provenance.softened_youngs_modulus_pa, code: $r.provenance.code_version,
       engine: $r.provenance.engine_version}' "$f"
  done
}

# Where atan(2H/D) falls short of the flank, split in two (degrees; they add up to
# flank - atan(2H/D)): the top, a flat crest c that cuts the cone of the flank angle phi, and the
# toe, the base beyond the flank lines. D_flank = c + 2H / tan(phi) is the base of the trapezoid
# of that crest and those flanks; toe_mm = D - D_flank; top_loss = phi - atan(2H / D_flank);
# toe_loss = atan(2H / D_flank) - atan(2H / D).
rows | jq -s 'map(. + (if .h_mm and .d_mm and .flank and .crest_mm then
    (3.141592653589793 / 180) as $rad |
    (.crest_mm + 2 * .h_mm / ((.flank * $rad | sin) / (.flank * $rad | cos)))  as $df |
    {toe_mm: (.d_mm - $df),
     top_loss: (.flank - ((2 * .h_mm / $df) | atan) / $rad),
     toe_loss: ((((2 * .h_mm / $df) | atan) - ((2 * .h_mm / .d_mm) | atan)) / $rad)}
  else {toe_mm: null, top_loss: null, toe_loss: null} end))' > "$out/runs.json"
jq -r '(["case","seed","status","stop","angle_deg","angle_sd_deg","H_mm","D_mm","flank_deg",
         "crest_mm","toe_mm","top_loss_deg","toe_loss_deg","bodies","components","grain",
         "mass_not_simulated","cpu_s","wall_s","dt_s",
         "softened_E_pa","code_version","engine_version"] | @csv),
       (.[] | [.case,.seed,.status,.stop,.angle,.angle_sd,.h_mm,.d_mm,.flank,.crest_mm,.toe_mm,
               .top_loss,.toe_loss,.bodies,
               .components,.grain,.not_simulated,.cpu_s,.wall_s,.dt_s,.e_soft_pa,.code,.engine]
        | @csv)' "$out/runs.json" > "$out/runs.csv"

jq -r '
  def r1: if . == null then "-" else (. * 10 | round / 10 | tostring) end;
  def pile: .status == "ok" and .stop == "settled";
  def ms(f): map(select(pile) | f | select(. != null)) |
    if length == 0 then "-" else (add / length) as $m |
      (if length > 1 then (map((. - $m) * (. - $m)) | add / (length - 1) | sqrt) else 0 end) as $s |
      "\($m | r1) ± \($s | r1)" end;
  "| case | piles / runs | atan(2H/D) [deg] | H [mm] | D [mm] | flank [deg] | crest [mm] | toe [mm] | loss at the top [deg] | loss at the toe [deg] | jams | unsettled | bodies | components | mass not simulated | CPU per run [s] |",
  "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
  (group_by(.case) | sort_by(.[0].case | if startswith("base") then "0" + . else . end)[] |
   "| \(.[0].case) | \(map(select(pile)) | length)/\(length) | \(ms(.angle)) | \(ms(.h_mm)) | \(ms(.d_mm)) | \(ms(.flank)) | \(ms(.crest_mm)) | \(ms(.toe_mm)) | \(ms(.top_loss)) | \(ms(.toe_loss)) | \(map(select(.status != "ok")) | length) | \(map(select(.status == "ok" and .stop != "settled")) | length) | \(map(.bodies) | add / length | round) | \(map(.components) | add / length | round) | \(.[0].not_simulated * 100 | round)% | \(map(.cpu_s // 0) | add / length | round) |")
' "$out/runs.json" > "$out/table.md"

# cases.dat: index, case, angle mean, sd, crest mean, sd (piles only); for the plot.
jq -r 'group_by(.case) | sort_by(.[0].case | if startswith("base") then "0" + . else . end) |
  to_entries[] | .key as $i | .value as $v | ($v | map(select(.status == "ok" and .stop == "settled"))) as $ok |
  def mean(f): ($ok | map(f | select(. != null))) as $x | if ($x | length) == 0 then "NaN" else ($x | add / length) end;
  def sd(f): ($ok | map(f | select(. != null))) as $x |
    if ($x | length) < 2 then 0 else ($x | add / length) as $m | ($x | map((. - $m) * (. - $m)) | add / (length - 1) | sqrt) end;
  "\($i) \($v[0].case) \(mean(.angle)) \(sd(.angle)) \(mean(.crest_mm)) \(sd(.crest_mm))"' \
  "$out/runs.json" > "$out/cases.dat"

n=$(wc -l < "$out/cases.dat")
gnuplot <<EOF
set terminal pngcairo size 1100,700 font ",10" noenhanced
set output "$out/crest_angle.png"
set multiplot layout 2,1 title "Pile-top study, Table 1 sample 4 (reduced): mean ± sd over the seeds that formed a pile"
set xrange [-0.7:$n-0.3]
set grid ytics
set ylabel "photo atan(2H/D) [deg]"
set yrange [*:38.5]
set xtics rotate by 35 right
set format x ""
set arrow 1 from -0.7,37.17 to $n-0.3,37.17 nohead dt 2 lc rgb "black"
set label 1 "lab 37.17 deg" at 0,37.6
plot "$out/cases.dat" using 1:3:4:xtic(2) with yerrorbars pt 7 lc rgb "#1f77b4" notitle
unset arrow 1
unset label 1
set format x "%g"
set ylabel "crest width [mm]"
set yrange [0:*]
plot "$out/cases.dat" using 1:5:6:xtic(2) with yerrorbars pt 5 lc rgb "#d62728" notitle
unset multiplot
EOF
echo "pile_top_table: $(jq length "$out/runs.json") runs -> $out/{runs.csv,table.md,crest_angle.png}"
