#!/usr/bin/env bash
# ab_pairs.sh: is binary B faster than binary A on this machine, whose speed drifts by up to 15%
# within minutes? Runs two bench_sim binaries alternately (A B, then B A, ...) on the same
# settled heap and prints the median, quartiles and range of time(B) / time(A) over the
# adjacent pairs, and each binary's final state hash (equal hashes: the same bits).
#
# Usage: bench/ab_pairs.sh --a BENCH_SIM_A --b BENCH_SIM_B --heap FILE
#                          [--threads 1] [--pairs 12] [--steps 300]
# FILE is a --heap checkpoint of bench_sim (written by the first run if it does not exist).
set -euo pipefail

a="" b="" heap="" threads=1 pairs=12 steps=300
while [[ $# -gt 0 ]]; do
  case "$1" in
    --a) a="$2"; shift 2 ;;
    --b) b="$2"; shift 2 ;;
    --heap) heap="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --pairs) pairs="$2"; shift 2 ;;
    --steps) steps="$2"; shift 2 ;;
    -h|--help) sed -n '2,9p' "$0"; exit 0 ;;
    *) echo "ab_pairs.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
for f in "$a" "$b"; do
  if [[ -z "$f" || ! -x "$f" ]]; then
    echo "ab_pairs.sh: --a and --b must name executable bench_sim binaries (got '$f')" >&2
    exit 2
  fi
done
if [[ -z "$heap" ]]; then echo "ab_pairs.sh: --heap FILE is required" >&2; exit 2; fi
positive='^[1-9][0-9]*$'
if ! [[ "$threads" =~ $positive && "$pairs" =~ $positive && "$steps" =~ $positive ]]; then
  echo "ab_pairs.sh: --threads, --pairs and --steps must be positive integers" >&2
  exit 2
fi

# One timed run: prints "seconds hash".
run() {
  OMP_WAIT_POLICY=active "$1" --heap "$heap" --steps "$steps" --threads "$threads" 2>&1 |
    sed -nE "s/.*threads ${threads}: [0-9]+ steps in ([0-9.]+) s wall.*hash (0x[0-9a-f]+).*/\1 \2/p"
}

ratios=()
hash_a="" hash_b=""
for ((p = 1; p <= pairs; ++p)); do
  if ((p % 2)); then ra=$(run "$a"); rb=$(run "$b"); else rb=$(run "$b"); ra=$(run "$a"); fi
  if [[ -z "$ra" || -z "$rb" ]]; then echo "ab_pairs.sh: a run printed no timing" >&2; exit 1; fi
  hash_a=${ra#* } hash_b=${rb#* }
  ratios+=("$(awk -v x="${rb% *}" -v y="${ra% *}" 'BEGIN { printf "%.5f", x / y }')")
done
printf '%s\n' "${ratios[@]}" | sort -g | awk -v n="${#ratios[@]}" -v ha="$hash_a" -v hb="$hash_b" '
  { r[NR] = $1 }
  END {
    med = (n % 2) ? r[(n + 1) / 2] : (r[n / 2] + r[n / 2 + 1]) / 2
    printf "time(B) / time(A): median %.4f, quartiles %.4f-%.4f, range %.4f-%.4f (%d pairs)\n",
           med, r[int((n + 3) / 4)], r[int((3 * n + 3) / 4)], r[1], r[n], n
    same = (ha == hb) ? " (the same bits)" : " (DIFFERENT bits)"
    printf "state hash A %s, B %s%s\n", ha, hb, same
  }'
