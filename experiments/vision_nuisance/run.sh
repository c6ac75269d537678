#!/usr/bin/env bash
# run.sh: regenerates the vision nuisance set (issue 51) from the committed piles and manifest,
# checks the POV-Ray camera against the project's projection, measures every photo with a
# reposetwin binary and prints the acceptance table (results/vision_nuisance/LABEL.csv, .md).
#
# Usage: experiments/vision_nuisance/run.sh [--bin BIN] [--label LABEL] [--work DIR] [--force]
#                                           [--piles] [--manifest]
#   --bin BIN     the binary measured (default build/apps/reposetwin/reposetwin)
#   --label L     results/vision_nuisance/L.csv and L.md (default: nuisance)
#   --work DIR    where the photos are rendered (default runs/vision_nuisance; not committed)
#   --force       render the photos again even when they exist
#   --piles       remake the pile CSVs too (the twin's runs with BIN, LIGGGHTS' pours; minutes)
#   --manifest    remake manifest.csv from the rules in make_set.py (after --piles)
# Installs the Debian packages it needs (povray, imagemagick; liggghts with --piles) if missing.
# Everything runs at nice 19. Exit 1 if the camera check fails.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "${here}/../.." && pwd)"
bin="${root}/build/apps/reposetwin/reposetwin"
label=nuisance
work="${root}/runs/vision_nuisance"
force=()
piles=0
manifest=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --bin) bin="$2"; shift 2 ;;
    --label) label="$2"; shift 2 ;;
    --work) work="$2"; shift 2 ;;
    --force) force=(--force); shift ;;
    --piles) piles=1; shift ;;
    --manifest) manifest=1; shift ;;
    -h|--help) sed -n '2,15p' "$0"; exit 0 ;;
    *) echo "run.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
[[ "${bin}" = /* ]] || bin="$(pwd)/${bin}"
[[ -x "${bin}" ]] || { echo "run.sh: ${bin}: no such executable (give --bin)" >&2; exit 2; }

need=(povray imagemagick)
[[ ${piles} -eq 1 ]] && need+=(liggghts)
missing=()
for p in "${need[@]}"; do
  dpkg-query -W -f='${Status}' "${p}" 2>/dev/null | grep -q "install ok installed" || missing+=("${p}")
done
if [[ ${#missing[@]} -gt 0 ]]; then
  echo "run.sh: installing ${missing[*]} (Debian packages)" >&2
  sudo_cmd=(); [[ "$(id -u)" -ne 0 ]] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >&2
fi
py=(nice -n 19 /usr/bin/python3)
[[ -x /usr/bin/python3 ]] || py=(nice -n 19 python3)

if [[ ${piles} -eq 1 ]]; then
  mkdir -p "${work}/piles"
  "${py[@]}" "${here}/piles.py" twin --bin "${bin}" --scene quick --seed 1 --out "${work}/piles" \
    --name twin_quick
  "${py[@]}" "${here}/piles.py" twin --bin "${bin}" --scene quick --seed 2 --out "${work}/piles" \
    --name twin_skirt --set "sample.psd_file=${root}/data/psd/dmax_5mm.toml" \
    --set sample.d_min_mm=1.7 --set contacts.rock-plate.rolling_friction=0.05
  "${py[@]}" "${here}/piles.py" liggghts --seed 1 --n 2000 --rate 1000 --settle 1.0 --mu-r 0.3 \
    --out "${work}/piles" --name liggghts_pour
  "${py[@]}" "${here}/piles.py" liggghts --seed 2 --n 3000 --rate 1000 --settle 1.0 --mu-r 0.15 \
    --out "${work}/piles" --name liggghts_pour_b
fi
if [[ ${manifest} -eq 1 ]]; then
  "${py[@]}" "${here}/make_set.py" manifest --out "${here}/manifest.csv"
fi

mkdir -p "${work}/photos"
"${py[@]}" "${here}/make_set.py" check --out "${work}" | tee "${work}/camera_check.txt"
t0=$(date +%s)
"${py[@]}" "${here}/make_set.py" render --manifest "${here}/manifest.csv" --out "${work}/photos" \
  "${force[@]}" | tee -a "${work}/render.log"
echo "render: $(( $(date +%s) - t0 )) s wall"
notes=(--note "$(tail -n 1 "${work}/camera_check.txt")")
rendered="$(grep '^rendered ' "${work}/render.log" | tail -n 1 || true)"
[[ -n "${rendered}" ]] && notes+=(--note "${rendered}")
"${py[@]}" "${here}/evaluate.py" --bin "${bin}" --manifest "${here}/manifest.csv" \
  --photos "${work}/photos" --label "${label}" --out-dir "${root}/results/vision_nuisance" \
  --command "experiments/vision_nuisance/run.sh --bin ${bin} --label ${label} --work ${work}" \
  "${notes[@]}"
