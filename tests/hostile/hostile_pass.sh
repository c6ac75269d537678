#!/usr/bin/env bash
# A hostile user's pass over the reposetwin command line (issue 41): bad --set values, bad
# files, bad flags and bad output folders against every command, on the tiny scene. Not part of
# ctest (it takes a few minutes and writes runs); run it by hand:
#
#   tests/hostile/hostile_pass.sh OUT_DIR [REPOSETWIN_BINARY]
#
# Every command runs under `timeout 20`, so a hang is counted, not suffered. Each case says which
# words a clean refusal must contain (the file, the key, the value; '~' separates alternatives)
# and is classified as:
#   clean    non-zero exit, the message names every word asked for
#   unclear  non-zero exit, the message misses one (or is a raw library/exception text)
#   silent   exit 0: a bad input accepted
#   hung     killed by the timeout
#   crashed  killed by a signal, or an uncaught exception / abort message
# Writes OUT_DIR/hostile_pass.csv (case,exit,class,message) and prints the counts. A run of it:
# results/reliability/ (README.md). REPOSETWIN_SOURCE overrides the source tree (for a copy).
set -u
OUT=$(realpath -m "${1:?usage: hostile_pass.sh OUT_DIR [BINARY]}")
SRC=${REPOSETWIN_SOURCE:-$(cd "$(dirname "$0")/../.." && pwd)}
BIN=$(realpath "${2:-$SRC/build/apps/reposetwin/reposetwin}")
W=$OUT/work
rm -rf "$W" && mkdir -p "$W" && cd "$W" || exit 1
CSV=$OUT/hostile_pass.csv
echo "case,exit,class,message" > "$CSV"
TINY=$W/tiny.toml
cp "$SRC/data/loop/tiny_scene.toml" "$TINY"

declare -A COUNT
csv_field() { local s=${1//\"/\"\"}; printf '"%s"' "$s"; }

# hc NAME WORDS CMD... : runs CMD, classifies it, appends a CSV row.
hc() {
  local name=$1 words=$2; shift 2
  local t0=$SECONDS rc
  timeout 20 "$@" > "$W/.out" 2> "$W/.err" < /dev/null
  rc=$?
  local dt=$((SECONDS - t0))
  local msg
  msg=$(grep -a -m1 -E 'reposetwin:|[Ee]rror|terminate|what\(\)' "$W/.err")
  [ -z "$msg" ] && msg=$(grep -a -v '^\s*$' "$W/.err" | head -n1)
  [ -z "$msg" ] && msg=$(grep -a -v '^\s*$' "$W/.out" | tail -n1)
  msg=$(printf '%s' "$msg" | tr -d '\r' | cut -c1-400)
  local all; all=$(cat "$W/.err" "$W/.out" | tr -d '\0')
  local class
  if [ $rc -eq 124 ] && [ $dt -ge 19 ]; then class=hung
  elif [ $rc -ge 128 ] || grep -a -q -E 'terminate called|Segmentation|Aborted|core dumped|AddressSanitizer' "$W/.err"; then class=crashed
  elif [ $rc -eq 0 ]; then class=silent
  else
    class=clean
    if grep -a -q -E 'std::|basic_string|filesystem error|json\.exception|\[json\.|bad_alloc|what\(\)' "$W/.err"; then class=unclear; fi
    local IFS='|' w
    for w in $words; do
      local found=0 alt
      local IFS='~'
      for alt in $w; do
        if [ -n "$alt" ] && printf '%s' "$all" | grep -a -q -F -- "$alt"; then found=1; fi
      done
      IFS='|'
      [ $found -eq 1 ] || class=unclear
    done
  fi
  echo "$(csv_field "$name"),$rc,$class,$(csv_field "$msg")" >> "$CSV"
  COUNT[$class]=$((${COUNT[$class]:-0} + 1))
  printf '%-44s %4s %-8s %s\n' "$name" "$rc" "$class" "${msg:0:150}"
}


# --- A finished run to measure, render and resume from (a valid baseline).
timeout 60 "$BIN" run "$TINY" -o "$W/base" -q > /dev/null 2>&1 || echo "baseline run failed"
SIDE=$(ls "$W"/base/images/side_*.png 2>/dev/null | grep -v measured | head -n1)
SIDEJ=${SIDE%.png}.json
TOP=$W/base/images/top.png

# run_sets SCENE: for each line "KEY VALUE..." on stdin, a run of SCENE with --set KEY=VALUE,
# whose refusal must name the key, the scene file and the value.
run_sets() {
  local scene=$1 key vals v
  while read -r key vals; do
    for v in $vals; do
      hc "run_set_${key}=${v}" \
        "$key|$(basename "$scene")|${v}~$(printf '%s' "$v" | sed 's/e300/e+300/')" \
        "$BIN" run "$scene" -o "$W/r_set" --no-images -q --set "$key=$v"
    done
  done
}

# --- 1. run --set: bad values of every kind of key (the key and the value named).
run_sets "$TINY" <<'KEYS'
sample.mass_kg 0 -1 nan inf 1e300 junk
materials.rock.density_kg_m3 0 nan inf 1e-300 1e300
materials.rock.youngs_modulus_pa 0 nan inf -5
materials.rock.poisson_ratio 0.5 -1.5 nan
materials.plate.youngs_modulus_pa nan
contacts.rock-rock.friction -0.1 inf nan
contacts.rock-rock.restitution 0 1.5 nan
contacts.rock-rock.rolling_friction -1 inf
contacts.rock-rock.rolling_model nonsense
contacts.rock-plate.cohesion_energy_density -1
container.bottom_diameter_m 0 -0.02 inf
container.top_diameter_m inf 0.001
container.height_m inf 0
container.kind teapot
container.material unobtainium
plate.material unobtainium
procedure.lift_speed_m_s 0 -1 inf
procedure.settle_speed_m_s 0 inf
procedure.fill_settle_max_s -1 nan
procedure.final_settle_max_s inf
procedure.max_time_s 0 1e300
procedure.lattice_gap 1e6 -1
procedure.fill_jitter 2
numerics.softened_youngs_modulus_pa 1e200 inf nan -1
numerics.time_step_s nan 0.01 -1e-5
numerics.gravity_m_s2 0 inf
numerics.threads -3 1.5
numerics.skin_m -1
output.frame_interval_s nan 1e-9 -1
output.progress_interval_s -1 nan
output.checkpoint_interval_s inf
output.contact_forces maybe
scene.seed -1 1.5
sample.d_min_mm 100
sample.psd.sieve_mm [4.0,3.0,2.0]
sample.psd.passing_percent [0.0,150.0,100.0]
measure.flank_low 0.9
measure.sectors 0
KEYS
# --- 1b. run --set on a grain-shape mix: every shape's keys as --set writes them.
{ cat "$TINY"; printf '%s\n' '[[sample.shapes]]' 'name = "rod"' 'kind = "generated"' \
    'mass_fraction = 0.5' 'elongation = 2.0' 'spheres = 3' '[[sample.shapes]]' 'name = "block"' \
    'kind = "blocky"' 'mass_fraction = 0.5' 'elongation = 1.5' 'angularity = 0.5'; } > "$W/mix.toml"
run_sets "$W/mix.toml" <<'KEYS'
sample.shapes.0.elongation 0.5 nan 1e300 9
sample.shapes.0.flatness 1e300 0
sample.shapes.0.spheres 0 65 1.5
sample.shapes.0.roundness 0 2
sample.shapes.0.kind teapot
sample.shapes.1.angularity 1 -1 nan
sample.shapes.1.mass_fraction 2 -0.5
sample.shapes.1.offsets [[0.0,0.0,0.0]]
KEYS
hc run_set_shape_index_beyond "sample.shapes.5" "$BIN" run "$W/mix.toml" -o "$W/r_u" --no-images -q --set sample.shapes.5.elongation=2
hc run_set_unknown_key "numerics.tiem_step_s" "$BIN" run "$TINY" -o "$W/r_u" --no-images -q --set numerics.tiem_step_s=1e-5
hc run_set_unknown_table "nosuch" "$BIN" run "$TINY" -o "$W/r_u" --no-images -q --set nosuch.key=1
hc run_set_unused_material_junk "materials.zzz.density_kg_m3|abc" "$BIN" run "$TINY" -o "$W/r_u" --no-images -q --set materials.zzz.density_kg_m3=abc
hc run_set_no_equals "--set~numerics.time_step_s" "$BIN" run "$TINY" -o "$W/r_u" --no-images -q --set numerics.time_step_s
hc run_set_empty "--set" "$BIN" run "$TINY" -o "$W/r_u" --no-images -q --set ""
hc run_set_twice_conflict "sample.mass_kg|-1" "$BIN" run "$TINY" -o "$W/r_u" --no-images -q --set sample.mass_kg=0.006 --set sample.mass_kg=-1
hc run_set_table_as_value "sample.psd" "$BIN" run "$TINY" -o "$W/r_u" --no-images -q --set sample.psd=3
hc run_set_psd_file_missing "sample.psd_file|nofile.csv" "$BIN" run "$TINY" -o "$W/r_u" --no-images -q --set sample.psd_file=nofile.csv
hc run_threads_neg "--threads" "$BIN" run "$TINY" -o "$W/r_u" --no-images -q --threads -1
hc run_threads_junk "--threads" "$BIN" run "$TINY" -o "$W/r_u" --no-images -q --threads many
hc run_max_hours_nan "--max-hours" "$BIN" run "$TINY" -o "$W/r_u" --no-images -q --max-hours nan
hc run_max_particles_0 "--max-particles" "$BIN" run "$TINY" -o "$W/r_u" --no-images -q --max-particles 0
hc run_big_plan_unconfirmed "particles~sample.mass_kg" "$BIN" run "$TINY" -o "$W/r_big" --no-images -q --set sample.mass_kg=200
hc run_unknown_flag "--frobnicate" "$BIN" run "$TINY" -o "$W/r_u" --frobnicate

# --- 2. bad scene files.
: > "$W/empty.toml"
head -c 4096 "$BIN" > "$W/binary.toml"
mkdir -p "$W/adir.toml"
mkfifo "$W/fifo.toml"
{ for i in $(seq 1 200000); do echo "# padding line $i of a huge comment block that goes on and on and on"; done; cat "$TINY"; } > "$W/huge.toml"
sed 's/^mass_kg = 0.006/mass_kg = "abc"/' "$TINY" > "$W/wrongtype.toml"
sed 's/^mass_kg = 0.006/mass_kg = 0.006\nmass_kgg = 0.006/' "$TINY" > "$W/unknownkey.toml"
{ cat "$TINY"; printf '\n[nosuch]\na = 1\n'; } > "$W/unknowntable.toml"
sed 's/^mass_kg = 0.006/mass_kg = 0.006\nmass_kg = 0.007/' "$TINY" > "$W/dupkey.toml"
sed 's/^name = "loop_tiny"/name = "lo\\u0000op"/' "$TINY" > "$W/nulname.toml"
sed 's/^mass_kg = 0.006/mass_kg = [0.006/' "$TINY" > "$W/syntax.toml"
sed '/^mass_kg = 0.006/d' "$TINY" > "$W/nomass.toml"
sed 's/^material = "rock"/material = "granite"/' "$TINY" > "$W/nomaterial.toml"
iconv -f utf-8 -t utf-16 "$TINY" > "$W/utf16.toml"
sed 's/^\[sample.psd\]/[sample.psdx]/' "$TINY" > "$W/nopsd.toml"
sed 's/^youngs_modulus_pa = 46.8e9/youngs_modulus_pa = 1e300/' "$TINY" > "$W/stiff.toml"
sed 's/^softened_youngs_modulus_pa = 5e6/softened_youngs_modulus_pa = 1e300/' "$TINY" > "$W/soft1e300.toml"
sed 's/^friction = 0.5/friction = nan/' "$TINY" > "$W/frictionnan.toml"
sed 's/^restitution = 0.5/restitution = inf/' "$TINY" > "$W/restinf.toml"
sed 's/rock-plate/rock-marble/' "$TINY" > "$W/badpair.toml"
hc scene_empty "empty.toml" "$BIN" run "$W/empty.toml" -o "$W/r_f" --no-images -q
hc scene_binary "binary.toml" "$BIN" run "$W/binary.toml" -o "$W/r_f" --no-images -q
hc scene_directory "adir.toml" "$BIN" run "$W/adir.toml" -o "$W/r_f" --no-images -q
hc scene_fifo "fifo.toml" "$BIN" run "$W/fifo.toml" -o "$W/r_f" --no-images -q
hc scene_dev_zero "/dev/zero" "$BIN" run /dev/zero -o "$W/r_f" --no-images -q
hc scene_dev_null "/dev/null" "$BIN" run /dev/null -o "$W/r_f" --no-images -q
hc scene_huge_comments_ok_is_silent_if_runs "huge.toml" "$BIN" run "$W/huge.toml" -o "$W/r_huge" --no-images -q --set sample.mass_kg=-1
hc scene_missing "nosuch.toml" "$BIN" run "$W/nosuch.toml" -o "$W/r_f" --no-images -q
hc scene_wrong_type "wrongtype.toml|mass_kg|abc" "$BIN" run "$W/wrongtype.toml" -o "$W/r_f" --no-images -q
hc scene_unknown_key "unknownkey.toml|mass_kgg" "$BIN" run "$W/unknownkey.toml" -o "$W/r_f" --no-images -q
hc scene_unknown_table "unknowntable.toml|nosuch" "$BIN" run "$W/unknowntable.toml" -o "$W/r_f" --no-images -q
hc scene_dup_key "dupkey.toml|mass_kg" "$BIN" run "$W/dupkey.toml" -o "$W/r_f" --no-images -q
hc scene_nul_in_name "nulname.toml|scene.name" "$BIN" run "$W/nulname.toml" -o "$W/r_f" --no-images -q
hc scene_syntax "syntax.toml:10" "$BIN" run "$W/syntax.toml" -o "$W/r_f" --no-images -q
hc scene_no_mass "nomass.toml|mass_kg" "$BIN" run "$W/nomass.toml" -o "$W/r_f" --no-images -q
hc scene_no_material "nomaterial.toml|granite" "$BIN" run "$W/nomaterial.toml" -o "$W/r_f" --no-images -q
hc scene_utf16 "utf16.toml" "$BIN" run "$W/utf16.toml" -o "$W/r_f" --no-images -q
hc scene_no_psd "nopsd.toml|psd" "$BIN" run "$W/nopsd.toml" -o "$W/r_f" --no-images -q
hc scene_E_1e300 "stiff.toml|youngs_modulus_pa|1e+300~1e300" "$BIN" run "$W/stiff.toml" -o "$W/r_f" --no-images -q
hc scene_softE_1e300 "soft1e300.toml|softened_youngs_modulus_pa|1e+300~1e300" "$BIN" run "$W/soft1e300.toml" -o "$W/r_f" --no-images -q
hc scene_friction_nan "frictionnan.toml|friction|nan" "$BIN" run "$W/frictionnan.toml" -o "$W/r_f" --no-images -q
hc scene_restitution_inf "restinf.toml|restitution|inf" "$BIN" run "$W/restinf.toml" -o "$W/r_f" --no-images -q
hc scene_missing_pair "badpair.toml|rock-plate~rock-marble" "$BIN" run "$W/badpair.toml" -o "$W/r_f" --no-images -q

# --- 3. output folders, resume and kill.
echo "not a folder" > "$W/afile"
mkdir -p "$W/foreign" && echo "<html>mine</html>" > "$W/foreign/summary.html"
hc out_at_file "afile" "$BIN" run "$TINY" -o "$W/afile" --no-images -q
hc out_under_file "afile" "$BIN" run "$TINY" -o "$W/afile/sub" --no-images -q
hc out_proc "/proc/reposetwin_x" "$BIN" run "$TINY" -o /proc/reposetwin_x --no-images -q
hc out_empty "--out" "$BIN" run "$TINY" -o "" --no-images -q
hc out_foreign_folder "foreign" "$BIN" run "$TINY" -o "$W/foreign" --no-images -q
hc out_finished_no_force "base|--force" "$BIN" run "$TINY" -o "$W/base" --no-images -q
hc resume_nothing "--resume~checkpoint" "$BIN" run "$TINY" -o "$W/r_none" --no-images -q --resume
hc resume_finished "base|finished" "$BIN" run "$TINY" -o "$W/base" --no-images -q --resume --set contacts.rock-rock.friction=0.4
hc resume_and_force "--resume|--force" "$BIN" run "$TINY" -o "$W/base" --no-images -q --resume --force
# A run killed part way, then a plain rerun into its folder (must say how to resume).
"$BIN" run "$TINY" -o "$W/killed" --no-images -q --set sample.mass_kg=0.06 --set output.checkpoint_interval_s=0.2 > /dev/null 2>&1 &
KPID=$!
# Killed as soon as its first checkpoint is written (a fixed sleep let a fast machine finish it).
for _ in $(seq 1 300); do
  [ -f "$W/killed/checkpoint.bin" ] && break
  sleep 0.1
done
kill -9 $KPID 2> /dev/null; wait $KPID 2> /dev/null
[ -f "$W/killed/result.json" ] && echo "note: the run to kill finished first; its cases test a finished run"
hc rerun_killed_plain "killed|--resume" "$BIN" run "$TINY" -o "$W/killed" --no-images -q --set sample.mass_kg=0.06 --set output.checkpoint_interval_s=0.2
hc resume_killed_changed "killed|scene~changed" "$BIN" run "$TINY" -o "$W/killed" --no-images -q --resume --set sample.mass_kg=0.06 --set output.checkpoint_interval_s=0.2 --set contacts.rock-rock.friction=0.4
if [ -f "$W/killed/checkpoint.bin" ]; then
  cp -r "$W/killed" "$W/corrupt"
  printf '\xff\xfe' | dd of="$W/corrupt/checkpoint.bin" bs=1 seek=1000 conv=notrunc 2> /dev/null
  hc resume_corrupt_checkpoint "checkpoint" "$BIN" run "$TINY" -o "$W/corrupt" --no-images -q --resume --set sample.mass_kg=0.06 --set output.checkpoint_interval_s=0.2
  cp -r "$W/killed" "$W/trunc" && truncate -s 100 "$W/trunc/checkpoint.bin"
  hc resume_truncated_checkpoint "checkpoint" "$BIN" run "$TINY" -o "$W/trunc" --no-images -q --resume --set sample.mass_kg=0.06 --set output.checkpoint_interval_s=0.2
fi

# --- 4. campaign.
cat > "$W/camp.toml" <<CAMP
name = "hostile"
scene = "tiny.toml"
seeds = [1]
[[case]]
name = "a"
overrides = { "contacts.rock-rock.rolling_friction" = 0.1 }
CAMP
sed 's/0.1 }/-5.0 }/' "$W/camp.toml" > "$W/camp_badval.toml"
sed 's/rolling_friction/rolling_frictoin/' "$W/camp.toml" > "$W/camp_badkey.toml"
sed 's/seeds = \[1\]/seeds = ["x"]/' "$W/camp.toml" > "$W/camp_badseeds.toml"
sed 's/tiny.toml/nosuch.toml/' "$W/camp.toml" > "$W/camp_noscene.toml"
{ cat "$W/camp.toml"; echo 'bogus = 1'; } > "$W/camp_unknown.toml"
{ cat "$W/camp.toml"; printf '[[case]]\nname = "a"\n'; } > "$W/camp_dupcase.toml"
sed 's/name = "a"/name = "..\/escape"/' "$W/camp.toml" > "$W/camp_badname.toml"
hc campaign_missing "nosuch_campaign.toml" "$BIN" campaign "$W/nosuch_campaign.toml" -o "$W/c1"
hc campaign_empty "empty.toml" "$BIN" campaign "$W/empty.toml" -o "$W/c1"
hc campaign_binary "binary.toml" "$BIN" campaign "$W/binary.toml" -o "$W/c1"
hc campaign_dir "adir.toml" "$BIN" campaign "$W/adir.toml" -o "$W/c1"
hc campaign_fifo "fifo.toml" "$BIN" campaign "$W/fifo.toml" -o "$W/c1"
hc campaign_bad_value "camp_badval.toml|rolling_friction|-5" "$BIN" campaign "$W/camp_badval.toml" -o "$W/c1" --no-images
hc campaign_bad_key "camp_badkey.toml|rolling_frictoin" "$BIN" campaign "$W/camp_badkey.toml" -o "$W/c1" --no-images
hc campaign_bad_seeds "camp_badseeds.toml|seeds" "$BIN" campaign "$W/camp_badseeds.toml" -o "$W/c1" --no-images
hc campaign_no_scene "camp_noscene.toml|nosuch.toml" "$BIN" campaign "$W/camp_noscene.toml" -o "$W/c1" --no-images
hc campaign_unknown_key "camp_unknown.toml|bogus" "$BIN" campaign "$W/camp_unknown.toml" -o "$W/c1" --no-images
hc campaign_dup_case "camp_dupcase.toml|a" "$BIN" campaign "$W/camp_dupcase.toml" -o "$W/c1" --no-images
hc campaign_bad_case_name "camp_badname.toml|escape" "$BIN" campaign "$W/camp_badname.toml" -o "$W/c1" --no-images
hc campaign_workers_0 "--workers" "$BIN" campaign "$W/camp.toml" -o "$W/c1" --workers 0 --no-images
hc campaign_workers_neg "--workers" "$BIN" campaign "$W/camp.toml" -o "$W/c1" --workers -2 --no-images
hc campaign_views_0 "--views" "$BIN" campaign "$W/camp.toml" -o "$W/c1" --views 0
hc campaign_views_huge "--views" "$BIN" campaign "$W/camp.toml" -o "$W/c1" --views 100000
hc campaign_mode_junk "--mode" "$BIN" campaign "$W/camp.toml" -o "$W/c1" --mode fork
hc campaign_out_at_file "afile" "$BIN" campaign "$W/camp.toml" -o "$W/afile" --no-images
hc campaign_scene_as_campaign "tiny.toml" "$BIN" campaign "$TINY" -o "$W/c1" --no-images

# --- 5. calibrate.
cat > "$W/cal.toml" <<CAL
name = "hcal"
scene = "tiny.toml"
seeds = [1]
[calibration]
key = ["contacts.rock-rock.rolling_friction"]
target_deg = 30.0
mu_r_range = [0.05, 0.4]
CAL
sed 's/target_deg = 30.0/target_deg = 95.0/' "$W/cal.toml" > "$W/cal_target95.toml"
sed 's/target_deg = 30.0/target_deg = nan/' "$W/cal.toml" > "$W/cal_targetnan.toml"
sed 's/\[0.05, 0.4\]/[0.4, 0.05]/' "$W/cal.toml" > "$W/cal_range_rev.toml"
sed 's/rock-rock.rolling_friction/rock-rock.rolling_frictoin/' "$W/cal.toml" > "$W/cal_badkey.toml"
sed '/target_deg/d' "$W/cal.toml" > "$W/cal_notarget.toml"
printf 'id,mass_kg,angle_deg\nt1,0.006,31\n' > "$W/tests_ok.csv"
printf 'id,mass_kg,angle_deg\nt1,0.006,131\n' > "$W/tests_angle.csv"
printf 'id,mass_kg,angle_deg\nt1,abc,31\n' > "$W/tests_mass.csv"
printf 'sieve_mm,passing_percent\n3.0,0\n4.0,-20\n' > "$W/sieve_bad.csv"
hc calibrate_missing "nosuch_cal.toml" "$BIN" calibrate "$W/nosuch_cal.toml" -o "$W/k1"
hc calibrate_empty "empty.toml" "$BIN" calibrate "$W/empty.toml" -o "$W/k1"
hc calibrate_dir "adir.toml" "$BIN" calibrate "$W/adir.toml" -o "$W/k1"
hc calibrate_fifo "fifo.toml" "$BIN" calibrate "$W/fifo.toml" -o "$W/k1"
hc calibrate_target_95 "cal_target95.toml|target_deg|95" "$BIN" calibrate "$W/cal_target95.toml" -o "$W/k1" --no-images
hc calibrate_target_nan "cal_targetnan.toml|target_deg|nan" "$BIN" calibrate "$W/cal_targetnan.toml" -o "$W/k1" --no-images
hc calibrate_range_reversed "cal_range_rev.toml|mu_r_range" "$BIN" calibrate "$W/cal_range_rev.toml" -o "$W/k1" --no-images
hc calibrate_bad_key "cal_badkey.toml|rolling_frictoin" "$BIN" calibrate "$W/cal_badkey.toml" -o "$W/k1" --no-images
hc calibrate_no_target "cal_notarget.toml|target" "$BIN" calibrate "$W/cal_notarget.toml" -o "$W/k1" --no-images
hc calibrate_no_calibration_table "camp.toml|calibration" "$BIN" calibrate "$W/camp.toml" -o "$W/k1" --no-images
hc calibrate_tests_no_scene "--scene" "$BIN" calibrate --tests "$W/tests_ok.csv" -o "$W/k1" --no-images
hc calibrate_tests_angle_131 "tests_angle.csv|angle_deg|131" "$BIN" calibrate --tests "$W/tests_angle.csv" --scene "$TINY" -o "$W/k1" --no-images
hc calibrate_tests_mass_abc "tests_mass.csv|mass_kg|abc" "$BIN" calibrate --tests "$W/tests_mass.csv" --scene "$TINY" -o "$W/k1" --no-images
hc calibrate_sieve_negative "sieve_bad.csv|passing" "$BIN" calibrate --tests "$W/tests_ok.csv" --scene "$TINY" --sieve "$W/sieve_bad.csv" -o "$W/k1" --no-images
hc calibrate_sieve_missing "nosieve.csv" "$BIN" calibrate --tests "$W/tests_ok.csv" --scene "$TINY" --sieve "$W/nosieve.csv" -o "$W/k1" --no-images
hc calibrate_mu_range_reversed "--mu-r-range" "$BIN" calibrate --tests "$W/tests_ok.csv" --scene "$TINY" --mu-r-range 0.5 0.1 -o "$W/k1" --no-images
hc calibrate_mu_range_nan "--mu-r-range" "$BIN" calibrate --tests "$W/tests_ok.csv" --scene "$TINY" --mu-r-range nan 0.3 -o "$W/k1" --no-images
hc calibrate_mu_range_negative "--mu-r-range" "$BIN" calibrate --tests "$W/tests_ok.csv" --scene "$TINY" --mu-r-range -0.5 0.3 -o "$W/k1" --no-images
hc calibrate_angle_junk "--angle" "$BIN" calibrate "$W/cal.toml" --angle protractor -o "$W/k1"
hc calibrate_only_unknown "nosuchtest" "$BIN" calibrate "$W/cal.toml" --only nosuchtest -o "$W/k1" --no-images
hc calibrate_workers_0 "--workers" "$BIN" calibrate "$W/cal.toml" --workers 0 -o "$W/k1" --no-images
hc calibrate_file_and_tests "--tests" "$BIN" calibrate "$W/cal.toml" --tests "$W/tests_ok.csv" -o "$W/k1" --no-images
hc calibrate_predict_only_none "cal.toml|--predict-only" "$BIN" calibrate "$W/cal.toml" --predict-only -o "$W/k_new" --no-images

# --- 6. loop.
D=$SRC/data/loop
cp "$D/example.csv" "$W/ok.csv"
head -n 3 "$D/example.csv" > "$W/hdr.csv"   # comments + header only
awk -F, 'BEGIN{OFS=","} /^#/ {print; next} NR>0 {print $0",0.005"}' "$W/ok.csv" | sed '0,/note,0.005/s/note,0.005/note,mass_kg/' > "$W/dupcol.csv"
sed 's/^id,role,scene,mass_kg,/id,role,scene,mass_kg,mass_g,/; s/^\(m[0-9]*_w[0-9]*,[a-z]*,tiny_scene.toml,[0-9.]*\),/\1,5,/' "$W/ok.csv" > "$W/mass_both.csv"
sed 's/^id,role,scene,mass_kg,/id,role,scene,mass_kg,set:sample.mass_kg,/; s/^\(m[0-9]*_w[0-9]*,[a-z]*,tiny_scene.toml,[0-9.]*\),/\1,0.007,/' "$W/ok.csv" > "$W/mass_set.csv"
sed 's/^m5_w20,calibrate,tiny_scene.toml,0.005/m5_w20,calibrate,tiny_scene.toml,abc/' "$W/ok.csv" > "$W/junkcell.csv"
sed 's/^m5_w20,calibrate,/m5_w20,calibrat,/' "$W/ok.csv" > "$W/badrole.csv"
sed 's/^m8_w20,/m5_w20,/' "$W/ok.csv" > "$W/dupid.csv"
sed 's/^m12_w20,calibrate,tiny_scene.toml,0.012,20,0.05,plate,,,30.9/m12_w20,calibrate,tiny_scene.toml,0.012,20,0.05,plate,,,95/' "$W/ok.csv" > "$W/angle95.csv"
sed 's/,tiny_scene.toml,/,.,/' "$W/ok.csv" > "$W/scenedot.csv"
sed 's/^\(m5_w20.*\),3,$/\1,3,,extra/' "$W/ok.csv" > "$W/extracell.csv"
sed 's/^m5_w20,calibrate,tiny_scene.toml,0.005,20,0.05,plate,8.1,31.0,,3,$/m5_w20,calibrate,tiny_scene.toml/' "$W/ok.csv" > "$W/shortrow.csv"
sed 's/^id,role,scene,mass_kg,W_mm/id,role,scene,mass_kg,W_cm/' "$W/ok.csv" > "$W/unknowncol.csv"
cp "$D/tiny_scene.toml" "$W/tiny_scene.toml"
hc loop_missing "nosuch.csv" "$BIN" loop "$W/nosuch.csv" -o "$W/l1"
hc loop_empty "empty.toml" "$BIN" loop "$W/empty.toml" -o "$W/l1"
hc loop_binary "binary.toml" "$BIN" loop "$W/binary.toml" -o "$W/l1"
hc loop_dir "adir.toml" "$BIN" loop "$W/adir.toml" -o "$W/l1"
hc loop_fifo "fifo.toml" "$BIN" loop "$W/fifo.toml" -o "$W/l1"
hc loop_header_only "hdr.csv" "$BIN" loop "$W/hdr.csv" -o "$W/l1"
hc loop_dup_column "dupcol.csv|mass_kg" "$BIN" loop "$W/dupcol.csv" -o "$W/l1"
hc loop_mass_kg_and_g "mass_both.csv|mass_kg|mass_g" "$BIN" loop "$W/mass_both.csv" -o "$W/l1"
hc loop_mass_and_set "mass_set.csv|mass_kg|set:sample.mass_kg" "$BIN" loop "$W/mass_set.csv" -o "$W/l1"
hc loop_junk_cell "junkcell.csv|mass_kg|abc" "$BIN" loop "$W/junkcell.csv" -o "$W/l1"
hc loop_bad_role "badrole.csv|role|calibrat" "$BIN" loop "$W/badrole.csv" -o "$W/l1"
hc loop_dup_id "dupid.csv|m5_w20" "$BIN" loop "$W/dupid.csv" -o "$W/l1"
hc loop_angle_95 "angle95.csv|angle_deg|95" "$BIN" loop "$W/angle95.csv" -o "$W/l1"
hc loop_scene_dot "scenedot.csv|scene" "$BIN" loop "$W/scenedot.csv" -o "$W/l1"
hc loop_extra_cell "extracell.csv|line~row" "$BIN" loop "$W/extracell.csv" -o "$W/l1"
hc loop_short_row "shortrow.csv|line~row" "$BIN" loop "$W/shortrow.csv" -o "$W/l1"
hc loop_unknown_column "unknowncol.csv|W_cm" "$BIN" loop "$W/unknowncol.csv" -o "$W/l1"
hc loop_mu_grid_junk "--mu-grid|abc" "$BIN" loop "$W/ok.csv" -o "$W/l1" --mu-grid 0.1,abc
hc loop_mu_grid_nan "--mu-grid|nan" "$BIN" loop "$W/ok.csv" -o "$W/l1" --mu-grid 0.1,nan
hc loop_mu_grid_negative "--mu-grid|-0.1" "$BIN" loop "$W/ok.csv" -o "$W/l1" --mu-grid -0.1,0.2
hc loop_seeds_junk "--seeds|x" "$BIN" loop "$W/ok.csv" -o "$W/l1" --seeds 1,x
hc loop_candidates_unknown "--candidates|warp_drive" "$BIN" loop "$W/ok.csv" -o "$W/l1" --candidates warp_drive
hc loop_refit_unknown "--refit|warp_drive" "$BIN" loop "$W/ok.csv" -o "$W/l1" --refit warp_drive
hc loop_mu_range_reversed "--mu-range" "$BIN" loop "$W/ok.csv" -o "$W/l1" --mu-range 0.4,0.02 --mu-range-reason x
hc loop_mu_range_no_reason "--mu-range-reason" "$BIN" loop "$W/ok.csv" -o "$W/l1" --mu-range 0.02,0.4
hc loop_width_0 "--width" "$BIN" loop "$W/ok.csv" -o "$W/l1" --width 0
hc loop_min_t_nan "--min-t" "$BIN" loop "$W/ok.csv" -o "$W/l1" --min-t nan
hc loop_at_bound_junk "--at-bound" "$BIN" loop "$W/ok.csv" -o "$W/l1" --at-bound sometimes
hc loop_out_at_file "afile" "$BIN" loop "$W/ok.csv" -o "$W/afile"

# --- 7. measure.
echo "not a png" > "$W/text.png"
: > "$W/empty.png"
mkdir -p "$W/adir.png"
mkfifo "$W/fifo.png"
if [ -n "$SIDE" ]; then
  python3 - "$SIDEJ" "$W" <<'PY'
import json, sys
src, w = sys.argv[1], sys.argv[2]
base = json.load(open(src))
def out(name, fn):
    j = json.loads(json.dumps(base)); fn(j); json.dump(j, open(f"{w}/{name}.json", "w"))
out("nofocal", lambda j: j["camera"]["intrinsics"].pop("focal_length_mm"))
out("nointr", lambda j: j["camera"].pop("intrinsics"))
out("k1big", lambda j: j["camera"]["intrinsics"].__setitem__("k1", 1e6))
out("unknownfield", lambda j: j.__setitem__("bogus_field", 1))
out("viewtop", lambda j: j.__setitem__("view", "top"))
out("widthneg", lambda j: j["camera"]["intrinsics"].__setitem__("width_px", -320))
out("focalstr", lambda j: j["camera"]["intrinsics"].__setitem__("focal_length_mm", "fifty"))
out("posnull", lambda j: j["camera"]["extrinsics"].__setitem__("position", None))
out("lookateq", lambda j: j["camera"]["extrinsics"].__setitem__("look_at", j["camera"]["extrinsics"]["position"]))
out("projjunk", lambda j: j["camera"].__setitem__("projection", "fisheye"))
PY
  printf '{"camera": ' > "$W/truncated.json"
  cp "$SIDE" "$W/side2.png"
  hc measure_missing_image "nosuch.png" "$BIN" measure "$W/nosuch.png"
  hc measure_text_png "text.png" "$BIN" measure "$W/text.png"
  hc measure_empty_png "empty.png" "$BIN" measure "$W/empty.png"
  hc measure_dir_png "adir.png" "$BIN" measure "$W/adir.png"
  hc measure_fifo_png "fifo.png" "$BIN" measure "$W/fifo.png"
  hc measure_mm_per_px_0 "--mm-per-px" "$BIN" measure "$SIDE" --mm-per-px 0
  hc measure_mm_per_px_nan "--mm-per-px" "$BIN" measure "$SIDE" --mm-per-px nan
  hc measure_camera_missing "nocam.json" "$BIN" measure "$SIDE" --camera "$W/nocam.json"
  hc measure_camera_truncated "truncated.json" "$BIN" measure "$SIDE" --camera "$W/truncated.json"
  hc measure_camera_binary "binary.toml" "$BIN" measure "$SIDE" --camera "$W/binary.toml"
  for s in nofocal nointr k1big unknownfield viewtop widthneg focalstr posnull lookateq projjunk; do
    field=$(case $s in nofocal) echo focal_length_mm;; nointr) echo intrinsics;; k1big) echo k1;;
      unknownfield) echo bogus_field;; viewtop) echo view;; widthneg) echo width_px;;
      focalstr) echo focal_length_mm;; posnull) echo position;; lookateq) echo look_at~position;;
      projjunk) echo projection;; esac)
    hc "measure_sidecar_$s" "$s.json|$field" "$BIN" measure "$SIDE" --camera "$W/$s.json"
  done
  hc measure_two_sides_one_camera "--camera" "$BIN" measure "$SIDE" --side "$W/side2.png" --camera "$SIDEJ"
  hc measure_roi_outside "roi|5000" "$BIN" measure "$SIDE" --mm-per-px 0.5 --roi 5000 5000 10 10
  hc measure_roi_negative "roi|-5" "$BIN" measure "$SIDE" --mm-per-px 0.5 --roi -5 0 10 10
  hc measure_flank_reversed "--flank-band|0.9~0.8" "$BIN" measure "$SIDE" --mm-per-px 0.5 --flank-band 0.9 0.1
  hc measure_flank_nan "--flank-band|nan" "$BIN" measure "$SIDE" --mm-per-px 0.5 --flank-band nan 0.8
  hc measure_top_missing "nosuch_top.png" "$BIN" measure "$SIDE" --top "$W/nosuch_top.png"
  hc measure_top_camera_is_side "view~top" "$BIN" measure "$SIDE" --top "$TOP" --top-camera "$SIDEJ"
  hc measure_scale_conflict "--mm-per-px|--camera" "$BIN" measure "$SIDE" --mm-per-px 0.5 --camera "$SIDEJ"
  hc measure_overlay_is_dir "adir.png" "$BIN" measure "$SIDE" --mm-per-px 0.5 --overlay "$W/adir.png"
fi

# --- 8. render.
hc render_missing_run "nosuch_run" "$BIN" render "$W/nosuch_run"
hc render_not_a_run "foreign" "$BIN" render "$W/foreign"
hc render_file_as_run "afile" "$BIN" render "$W/afile"
hc render_views_0 "--views" "$BIN" render "$W/base" --views 0
hc render_views_100000 "--views" "$BIN" render "$W/base" --views 100000
hc render_width_1 "--width" "$BIN" render "$W/base" --width 1
hc render_height_huge "--height" "$BIN" render "$W/base" --height 100000
hc render_camera_height_neg "--camera-height" "$BIN" render "$W/base" --camera-height -1
hc render_camera_height_nan "--camera-height" "$BIN" render "$W/base" --camera-height nan
hc render_frame_missing "frame_99999.vtp" "$BIN" render "$W/base" --force --frame frames/frame_99999.vtp
hc render_camera_bad "nofocal.json|focal_length_mm" "$BIN" render "$W/base" --camera "$W/nofocal.json" --force
hc render_no_force "--force" "$BIN" render "$W/base"
cp -r "$W/base" "$W/badvtp" && head -c 500 "$W/base/final.vtp" > "$W/badvtp/final.vtp"
hc render_truncated_vtp "final.vtp" "$BIN" render "$W/badvtp" --force

# --- 9. export.
echo "junk" > "$W/junk.vtp"
hc export_no_out "--out" "$BIN" export "$TINY"
hc export_out_at_file "afile" "$BIN" export "$TINY" -o "$W/afile"
hc export_bad_set "sample.mass_kg|-1" "$BIN" export "$TINY" -o "$W/e1" --set sample.mass_kg=-1
hc export_missing_scene "nosuch.toml" "$BIN" export "$W/nosuch.toml" -o "$W/e1"
hc export_scene_dir "adir.toml" "$BIN" export "$W/adir.toml" -o "$W/e1"
hc export_initial_state_missing "nosuch.vtp" "$BIN" export "$TINY" -o "$W/e2" --initial-state "$W/nosuch.vtp"
hc export_initial_state_junk "junk.vtp" "$BIN" export "$TINY" -o "$W/e3" --initial-state "$W/junk.vtp"
hc export_seed_neg "--seed" "$BIN" export "$TINY" -o "$W/e4" --seed -1
timeout 20 "$BIN" export "$TINY" -o "$W/e5" > /dev/null 2>&1
hc export_existing_no_force "e5|--force" "$BIN" export "$TINY" -o "$W/e5"
hc export_unknown_key "nosuch" "$BIN" export "$TINY" -o "$W/e6" --set nosuch.x=1

# --- 10. keys.
hc keys_unknown_flag "--bogus" "$BIN" keys --bogus
hc keys_extra_arg "extra" "$BIN" keys extra
hc keys_markdown_value "--markdown" "$BIN" keys --markdown=maybe

echo
tried=0
for c in clean unclear silent hung crashed; do
  echo "$c: ${COUNT[$c]:-0}"
  tried=$((tried + ${COUNT[$c]:-0}))
done
echo "tried: $tried"
