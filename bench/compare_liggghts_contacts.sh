#!/usr/bin/env bash
# compare_liggghts_contacts.sh: the contact laws of the twin and of LIGGGHTS 3.8 compared one
# contact at a time. bench_contact_trace runs each case (a sphere sliding onto the plate, an
# oblique pair impact, a sphere resting on another) in our engine and writes the same case for
# LIGGGHTS; LIGGGHTS runs it on one rank; the two traces are printed side by side at a few steps
# with the largest differences in position [um], velocity [mm/s] and angular velocity [rad/s].
# Not CI: it installs the Debian packages liggghts and openmpi-bin if they are missing.
#
# Usage: bench/compare_liggghts_contacts.sh [--cases plate_slide,pair_oblique,pair_rest]
#                                           [--steps N] [--mu-r X] [--build DIR] [--work DIR]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cases=plate_slide,pair_oblique,pair_rest
steps=6000
mu_r=0.4
build="${root}/build"
work=runs/contact_traces
while [[ $# -gt 0 ]]; do
  case "$1" in
    --cases|--steps|--mu-r|--build|--work)
      [[ $# -ge 2 ]] || { echo "compare_liggghts_contacts.sh: $1 needs a value" >&2; exit 2; }
      case "$1" in
        --cases) cases="$2" ;; --steps) steps="$2" ;; --mu-r) mu_r="$2" ;;
        --build) build="$2" ;; --work) work="$2" ;;
      esac
      shift 2 ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) echo "compare_liggghts_contacts.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
[[ "${steps}" =~ ^[1-9][0-9]*$ ]] ||
  { echo "compare_liggghts_contacts.sh: --steps must be a positive integer (got '${steps}')" >&2; exit 2; }
if ! command -v liggghts >/dev/null; then
  echo "installing liggghts (Debian package) ..." >&2
  sudo_cmd=(); [[ "$(id -u)" -ne 0 ]] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends \
    liggghts openmpi-bin >&2
fi
bin="${build}/bench/bench_contact_trace"
if [[ ! -x "${bin}" ]]; then
  cmake -S "${root}" -B "${build}" >/dev/null && cmake --build "${build}" -j2 --target bench_contact_trace
fi
IFS=, read -r -a list <<< "${cases}"
for c in "${list[@]}"; do
  dir="${work}/${c}"
  mkdir -p "${dir}"
  "${bin}" --case "${c}" --steps "${steps}" --every 50 --mu-r "${mu_r}" \
    --write-liggghts "${dir}" > "${dir}/ours.csv"
  (cd "${dir}" && liggghts -in in.trace > liggghts.log 2>&1) ||
    { echo "compare_liggghts_contacts.sh: LIGGGHTS failed on ${c}: ${dir}/liggghts.log" >&2; exit 1; }
  python3 - "${dir}" "${c}" <<'PY'
import sys, math
d, name = sys.argv[1], sys.argv[2]
ours = {}
for line in open(f"{d}/ours.csv"):
    if line.startswith("#") or line.startswith("step"): continue
    f = line.strip().split(",")
    ours[(int(f[0]), int(f[1]))] = [float(v) for v in f[2:]]
lig, step, lines = {}, None, open(f"{d}/trace.dump").read().split("\n")
i = 0
while i < len(lines):
    if lines[i].startswith("ITEM: TIMESTEP"):
        step = int(lines[i + 1]); i += 2; continue
    if lines[i].startswith("ITEM: ATOMS"):
        i += 1
        while i < len(lines) and lines[i] and not lines[i].startswith("ITEM"):
            f = lines[i].split()
            lig[(step, int(f[0]))] = [float(v) for v in f[1:]]
            i += 1
        continue
    i += 1
keys = sorted(k for k in ours if k in lig)
if not keys:
    sys.exit(f"compare_liggghts_contacts.sh: {name}: no common rows")
worst = [0.0, 0.0, 0.0]
for k in keys:
    a, b = ours[k], lig[k]
    worst[0] = max(worst[0], max(abs(a[j] - b[j]) for j in range(3)) * 1e6)
    worst[1] = max(worst[1], max(abs(a[j] - b[j]) for j in range(3, 6)) * 1e3)
    worst[2] = max(worst[2], max(abs(a[j] - b[j]) for j in range(6, 9)))
print(f"== {name}: {len(keys)} rows; largest difference: position {worst[0]:.3g} um, "
      f"velocity {worst[1]:.3g} mm/s, angular velocity {worst[2]:.3g} rad/s")
last = max(s for s, _ in keys)
for s in sorted({s for s, _ in keys}):
    if s not in (0, last) and s % (last // 6 or 1): continue
    for k in [kk for kk in keys if kk[0] == s]:
        a, b = ours[k], lig[k]
        print(f"step {s:6d} id {k[1]}  x/mm ours {a[0]*1e3:9.4f} {a[2]*1e3:9.4f} lig {b[0]*1e3:9.4f} "
              f"{b[2]*1e3:9.4f}   v/mm/s ours {a[3]*1e3:8.3f} lig {b[3]*1e3:8.3f}   "
              f"w/rad/s ours {a[7]:9.4f} lig {b[7]:9.4f}")
PY
done
