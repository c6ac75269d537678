#!/usr/bin/env bash
# verify_yade_clumps.sh: one column collapse of tetrahedral four-sphere clumps, and of spheres of
# the same radii, run by the twin's engine and by Yade (Debian's package) from identical settled
# beds, both measured by the twin's particle measure (H, D, atan(2H/D), slice angle); prints both
# engines' means and seed spreads per case, their difference with its 2 standard errors, and
# the clumps-minus-spheres trend in each engine (issue 37: is the trend physics or our code?).
#
# The case (bench_clumps --collapse; its design note): N clumps (component radius 0.5-0.6 mm,
# centres 0.9 r from the body's centre, random orientations, six template sizes) start on a
# jittered lattice in a cylinder (radius --container-mm) on a plate, settle at 5 g then relax at
# 1 g with a velocity damping, all in the twin; the settled bed (positions, velocities, masses,
# principal moments) is written for Yade, the container is removed at t = 0 in both engines, and
# both run the same number of steps of the same dt; the final spheres are written
# (Yade: "x y z radius"; the twin: its own .vtp) and measured by `reposetwin measure-particles`
# for both. The script checks that Yade's bed as built holds bed.txt's spheres. The sphere case is the
# same with 4N spheres. Seeds change the sizes, orientations and jitter: different beds.
#
# The contact law, matched as closely as the two engines allow: Hertz normal spring
# (4/3 E* sqrt(R*) delta^1.5), Mindlin no-slip tangential spring 8 G* sqrt(R* delta) on an
# incremental displacement with a Coulomb cap mu_s |F_n|, Tsuji's viscous dashpots from e
# (2 sqrt(5/6) |beta| sqrt(S m*), normal and tangential), no rolling resistance on either side
# (Yade's Law2_ScGeom_MindlinPhys_Mindlin has none; the twin runs with rolling model "none"), no
# global damping, the same E (softened 46.8 MPa), nu 0.19, density 2760, e 0.79, mu_s 0.466
# (plate too), dt 4.10e-6 s. Yade's inputs are adjusted where its defaults differ (collapse.py
# says how; scripts/yade_contact_check.py checks the springs and dashpots on single Yade contacts
# against the twin's closed forms before the runs):
# the plate's E so that Yade's wall contact (R* = r/2) gets the twin's springs, beta_n = beta_s
# so that its dashpots are the twin's (its en = e gives 5% more), the clump members' mass so that
# m* is the bodies' as in the twin. What remains different:
#  - the contact springs of the settled bed: the twin keeps them, Yade starts them at zero;
#  - the end of a contact and slip: the twin lets the normal dashpot make the force slightly
#    attractive and drops the tangential dashpot in slip; Yade's Law2 follows its own rules there;
#  - the integrators (the twin's velocity Verlet with its free-rotor drift for bodies, Yade's
#    leap-frog NewtonIntegrator with exactAsphericalRot) and the relative velocity at the contact
#    (Yade's mid-step incident velocity), so trajectories part within the first collisions and
#    only the seed statistics can agree.
# Not CI: it installs the Debian package yade if it is missing (no GUI recommends).
#
# Usage: scripts/verify_yade_clumps.sh [--seeds 1,2,3,4,5] [--clumps 400] [--container-mm 7]
#                                      [--steps 70000] [--jobs 2] [--out DIR] [--build DIR]
# Results: DIR/summary.csv (one row per seed, case and engine; its ke_end_J is the twin's
# translational + rotational energy but Yade's translational only), DIR/summary.json (means, sd,
# differences unpaired and paired by seed, trends) and the table on stdout. Runs that already
# wrote their output are not run again.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
seeds=1,2,3,4,5
clumps=400
container_mm=7
steps=70000
jobs=2
out=runs/verify_yade_clumps
build="${root}/build"
need() { [[ $# -ge 2 ]] || { echo "verify_yade_clumps.sh: $1 needs a value" >&2; exit 2; }; }
while [[ $# -gt 0 ]]; do
  case "$1" in
    --seeds) need "$@"; seeds="$2"; shift 2 ;;
    --clumps) need "$@"; clumps="$2"; shift 2 ;;
    --container-mm) need "$@"; container_mm="$2"; shift 2 ;;
    --steps) need "$@"; steps="$2"; shift 2 ;;
    --jobs) need "$@"; jobs="$2"; shift 2 ;;
    --out) need "$@"; out="$2"; shift 2 ;;
    --build) need "$@"; build="$2"; shift 2 ;;
    -h|--help) sed -n '2,44p' "$0"; exit 0 ;;
    *) echo "verify_yade_clumps.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
[[ "${seeds}" =~ ^[0-9]+(,[0-9]+)*$ ]] ||
  { echo "verify_yade_clumps.sh: --seeds must be a list like 1,2,3 (got '${seeds}')" >&2; exit 2; }
for kv in "clumps=${clumps}" "steps=${steps}" "jobs=${jobs}"; do
  [[ "${kv#*=}" =~ ^[1-9][0-9]*$ ]] ||
    { echo "verify_yade_clumps.sh: --${kv%%=*} must be a positive integer (got '${kv#*=}')" >&2; exit 2; }
done
[[ "${container_mm}" =~ ^[0-9]+([.][0-9]+)?$ ]] ||
  { echo "verify_yade_clumps.sh: --container-mm must be a positive number (got '${container_mm}')" >&2; exit 2; }

if ! command -v yade > /dev/null; then
  echo "installing yade (Debian package) ..." >&2
  sudo_cmd=(); [[ "$(id -u)" -ne 0 ]] && sudo_cmd=(sudo)
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends yade >&2
fi
yade_version="$(dpkg-query -W -f '${Version}' yade 2> /dev/null || echo unknown)"
bench="${build}/bench/bench_clumps"
bin="${build}/apps/reposetwin/reposetwin"
for t in bench_clumps:"${bench}" reposetwin:"${bin}"; do
  [[ -x "${t#*:}" ]] || cmake --build "${build}" -j2 --target "${t%%:*}"
done
# measure-particles reads its [measure] settings from a scene; this one keeps the defaults.
scene="${root}/data/scenes/paper/table1_s4_dmax8p0_900g_reduced.toml"
commit="$(git -C "${root}" rev-parse --short HEAD 2> /dev/null || echo unknown)"
dirty="$(git -C "${root}" status --porcelain --untracked-files=no 2> /dev/null | head -c1)"
[[ -n "${dirty}" ]] && commit+="-dirty"

mkdir -p "${out}"
echo "verify_yade_clumps: commit ${commit}, yade ${yade_version}, ${clumps} clumps / $((4 * clumps))" \
  "spheres, container ${container_mm} mm, ${steps} steps, seeds ${seeds}; load $(cut -d' ' -f1-3 /proc/loadavg)"
IFS=, read -r -a seed_list <<< "${seeds}"

# 1. The twin: settle each seed's two beds, write Yade's inputs, run the collapse (one thread).
for s in "${seed_list[@]}"; do
  d="${out}/seed_${s}"
  [[ -f "${d}/clumps/twin.vtp" && -f "${d}/spheres/twin.vtp" ]] && continue
  OMP_NUM_THREADS=1 OMP_WAIT_POLICY=passive "${bench}" --clumps "${clumps}" \
    --container-mm "${container_mm}" --settle 15000 --relax 3000 --settle-threads 1 \
    --rolling-friction 0 --seed "${s}" --collapse "${d}" --collapse-steps "${steps}" \
    > "${d}.twin.log" 2>&1 ||
    { echo "verify_yade_clumps.sh: the twin failed on seed ${s}: ${d}.twin.log" >&2; tail -5 "${d}.twin.log" >&2; exit 1; }
  grep -E '^COLLAPSE' "${d}.twin.log" | sed "s/^/  seed ${s}: /"
done

# 2. Yade's contact law, checked on single contacts against the twin's closed forms with the
#    first collapse.py's parameters (scripts/yade_contact_check.py), then Yade on the same beds,
#    --jobs runs at a time, one thread each.
first="${out}/seed_${seed_list[0]}/clumps"
(cd "${first}" && COLLAPSE_PY=collapse.py OMP_NUM_THREADS=1 \
  yade -j1 -n -x "${root}/scripts/yade_contact_check.py" > contact_check.log 2>&1) ||
  { echo "verify_yade_clumps.sh: Yade's contacts are not the twin's law:" >&2
    grep -E 'CHECK|Error' "${first}/contact_check.log" >&2; exit 1; }
grep -E '^YADE_CONTACT_CHECK ok' "${first}/contact_check.log" > /dev/null ||
  { echo "verify_yade_clumps.sh: ${first}/contact_check.log: the contact check did not finish" >&2; exit 1; }
echo "  Yade's contacts (sphere-plate, sphere-sphere, clump-clump) follow the twin's closed forms" \
  "($(grep -c '^CHECK' "${first}/contact_check.log") checks, ${first}/contact_check.log)"
run_yade() {  # run_yade DIR
  (cd "$1" && OMP_NUM_THREADS=1 yade -j1 -n -x collapse.py > yade.log 2>&1) ||
    { echo "verify_yade_clumps.sh: Yade failed in $1 (see $1/yade.log)" >&2; tail -5 "$1/yade.log" >&2; return 1; }
  echo "  $1: $(grep '^YADE_COLLAPSE' "$1/yade.log")"
}
pending=()
for s in "${seed_list[@]}"; do
  for c in clumps spheres; do
    [[ -f "${out}/seed_${s}/${c}/final.dump" ]] || pending+=("${out}/seed_${s}/${c}")
  done
done
for d in "${pending[@]}"; do
  while [[ $(jobs -rp | wc -l) -ge ${jobs} ]]; do wait -n || true; done
  run_yade "${d}" &
done
wait || true
for d in "${pending[@]}"; do
  [[ -f "${d}/final.dump" ]] || { echo "verify_yade_clumps.sh: Yade wrote no ${d}/final.dump" >&2; exit 1; }
done

# 3. Identical inputs: Yade's bed as it built it (initial.dump) holds bed.txt's spheres.
for s in "${seed_list[@]}"; do
  for c in clumps spheres; do
    python3 - "${out}/seed_${s}/${c}" <<'PY' || exit 1
import sys
d = sys.argv[1]
bed = []
for line in open(d + '/bed.txt'):
    if line.startswith('#'):
        continue
    v = [float(t) for t in line.split()]
    bed += [tuple(v[11 + 4 * i:15 + 4 * i]) for i in range(int(v[10]))]
rows = open(d + '/initial.dump').read().split('ITEM: ATOMS x y z radius\n')[1].split()
yade = [tuple(float(t) for t in rows[k:k + 4]) for k in range(0, len(rows), 4)]
bed.sort(); yade.sort()
if len(bed) != len(yade):
    sys.exit('verify_yade_clumps.sh: %s: Yade built %d spheres of the bed\'s %d' % (d, len(yade), len(bed)))
worst = max(max(abs(a - b) for a, b in zip(p, q)) for p, q in zip(bed, yade))
if worst > 1e-12:
    sys.exit('verify_yade_clumps.sh: %s: Yade built the bed %.3g m away from bed.txt' % (d, worst))
PY
  done
done
echo "  Yade's beds hold the twin's spheres (centres and radii within 1e-12 m)"

# 4. Both measured by the same code; the table and the statistics.
csv="${out}/summary.csv"
echo "seed,case,engine,status,H_mm,D_mm,theta_hd_deg,slice_angle_deg,pile_spheres,spheres,cpu_s,ke_end_J" > "${csv}.tmp"
field() { tr ' ' '\n' <<< "$1" | sed -n "s/^$2=//p"; }
for s in "${seed_list[@]}"; do
  for c in clumps spheres; do
    d="${out}/seed_${s}/${c}"
    for e in twin yade; do
      if [[ ${e} == twin ]]; then
        dump="${d}/twin.vtp"; line="$(grep "^COLLAPSE bed=${c} " "${out}/seed_${s}.twin.log")"
      else
        dump="${d}/final.dump"; line="$(grep '^YADE_COLLAPSE' "${d}/yade.log")"
      fi
      "${bin}" measure-particles "${dump}" --scene "${scene}" --json > "${d}/${e}.measure.json"
      python3 - "${d}/${e}.measure.json" "${s},${c},${e}" "$(field "${line}" cpu_seconds)" \
        "$(field "${line}" ke_end)" >> "${csv}.tmp" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
# No flank fit: no slice angle (nan), H and D still measured.
slice_angle = m['slice_angle_mean_deg'] if m['status'] == 'ok' else float('nan')
print('%s,%s,%.3f,%.3f,%.3f,%.3f,%d,%d,%s,%s' % (
    sys.argv[2], m['status'].replace(' ', '_'), 1e3 * m['height_m'], 1e3 * m['base_diameter_m'],
    m['theta_hd_deg'], slice_angle, m['pile_count'], m['particles'], sys.argv[3], sys.argv[4]))
PY
    done
  done
done
mv "${csv}.tmp" "${csv}"
python3 - "${csv}" "${out}/summary.json" "${commit}" "${yade_version}" "${clumps}" \
  "${container_mm}" "${steps}" <<'PY'
import csv, json, math, os, sys
rows = list(csv.DictReader(open(sys.argv[1])))
metrics = ['H_mm', 'D_mm', 'theta_hd_deg', 'slice_angle_deg', 'pile_fraction']
for r in rows:  # the share of the spheres in the pile: the rest ran out as strays
    r['pile_fraction'] = str(float(r['pile_spheres']) / float(r['spheres']))
def stats(v):
    v = [x for x in v if not math.isnan(x)]
    n = len(v)
    if n == 0:
        return {'n': 0, 'mean': float('nan'), 'sd': float('nan')}
    m = sum(v) / n
    sd = math.sqrt(sum((x - m) ** 2 for x in v) / (n - 1)) if n > 1 else float('nan')
    return {'n': n, 'mean': m, 'sd': sd}
out = {'commit': sys.argv[3], 'yade': sys.argv[4], 'clumps': int(sys.argv[5]),
       'container_mm': float(sys.argv[6]), 'steps': int(sys.argv[7]), 'cases': {}}
for r in rows:
    print('seed %-3s %-7s %-4s %-6s H %5.2f mm  D %6.2f mm  atan(2H/D) %6.2f  slice %6.2f deg  '
          '%4s of %4s spheres in the pile  CPU %6.1f s' % (r['seed'], r['case'], r['engine'],
          r['status'], float(r['H_mm']), float(r['D_mm']), float(r['theta_hd_deg']),
          float(r['slice_angle_deg']), r['pile_spheres'], r['spheres'], float(r['cpu_s'])))
print()
def se_diff(a, b):
    if a['n'] < 2 or b['n'] < 2:
        return float('nan')
    return math.sqrt(a['sd'] ** 2 / a['n'] + b['sd'] ** 2 / b['n'])
for case in ('clumps', 'spheres'):
    c = out['cases'][case] = {}
    for k in metrics:
        s = {e: stats([float(r[k]) for r in rows if r['case'] == case and r['engine'] == e and
                       r['status'] != 'no_pile']) for e in ('twin', 'yade')}
        d = s['twin']['mean'] - s['yade']['mean']
        se = se_diff(s['twin'], s['yade'])
        z = d / se if se > 0 else float('nan')
        # Paired by seed: both engines start from the same bed, so the per-seed difference
        # removes the beds' share of the spread.
        by = {(r['seed'], r['engine']): float(r[k]) for r in rows if r['case'] == case}
        p = stats([by[(sd, 'twin')] - by[(sd, 'yade')] for sd in sorted({r['seed'] for r in rows})
                   if (sd, 'twin') in by and (sd, 'yade') in by])
        p['se'] = p['sd'] / math.sqrt(p['n']) if p['n'] > 1 else float('nan')
        pz = p['mean'] / p['se'] if p['se'] > 0 else float('nan')
        c[k] = {'twin': s['twin'], 'yade': s['yade'], 'difference': d, 'se': se,
                'difference_in_se': z, 'paired': dict(p, difference_in_se=pz)}
        verdict = ('agree within 2 se' if abs(d) <= 2 * se else 'DIFFER beyond 2 se') \
            if se > 0 else 'no spread to compare with'
        print('%-7s %-15s twin %7.2f +- %5.2f  yade %7.2f +- %5.2f  (n %d, %d)  difference %+6.2f '
              '(se %.2f, %+.1f se): %s' % (case, k, s['twin']['mean'], s['twin']['sd'],
              s['yade']['mean'], s['yade']['sd'], s['twin']['n'], s['yade']['n'], d, se, z,
              verdict))
        print('%-7s %-15s paired by seed: %+6.2f (se %.2f, %+.1f se, n %d): %s' % (
              case, '', p['mean'], p['se'], pz, p['n'],
              ('agree within 2 se' if abs(pz) <= 2 else 'DIFFER beyond 2 se')
              if p['se'] > 0 else 'no spread to compare with'))
print()
out['trend'] = {}
for e in ('twin', 'yade'):
    t = out['trend'][e] = {}
    for k in ('H_mm', 'theta_hd_deg', 'slice_angle_deg', 'pile_fraction'):
        a, b = out['cases']['clumps'][k][e], out['cases']['spheres'][k][e]
        d, se = a['mean'] - b['mean'], se_diff(a, b)
        t[k] = {'clumps_minus_spheres': d, 'se': se}
        print('trend %-4s %-15s clumps - spheres %+7.3f (se %.3f)' % (e, k, d, se))
tmp = sys.argv[2] + '.tmp'
json.dump(out, open(tmp, 'w'), indent=2)
os.replace(tmp, sys.argv[2])
PY
