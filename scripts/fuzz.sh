#!/usr/bin/env bash
# Runs each fuzz harness (fuzz/) under libFuzzer for a bounded time, with AddressSanitizer and
# UndefinedBehaviorSanitizer, starting from the committed corpus. Usage:
#   scripts/fuzz.sh [SECONDS_PER_HARNESS (default 30)] [HARNESS...]   (scene lab_csv sidecar image)
# Builds an instrumented copy of the project with clang in build-fuzz/ (the first build takes a
# while). New inputs go to build-fuzz/corpus/<harness>/, findings to build-fuzz/findings/: a
# finding's input belongs in fuzz/corpus/<harness>/ once fixed, where ctest replays it.
# Exit status: 0 when no harness found anything, 1 otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_EACH=${1:-30}
shift || true
HARNESSES=("$@")
[ ${#HARNESSES[@]} -gt 0 ] || HARNESSES=(scene lab_csv sidecar image)

scripts/install_deps.sh --fuzz
SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined"
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link $SAN" \
  -DCMAKE_EXE_LINKER_FLAGS="$SAN" \
  -DREPOSETWIN_FUZZ=ON -DREPOSETWIN_BUILD_TESTS=OFF -DREPOSETWIN_BUILD_BENCH=OFF >/dev/null
targets=()
for h in "${HARNESSES[@]}"; do targets+=("fuzz_$h"); done
cmake --build build-fuzz -j"$(nproc)" --target "${targets[@]}"

mkdir -p build-fuzz/findings
status=0
for h in "${HARNESSES[@]}"; do
  mkdir -p "build-fuzz/corpus/$h"
  log="build-fuzz/fuzz_$h.log"
  # A grain scene or a photo can take a while to parse or measure: 10 s per input is a hang.
  if ASAN_OPTIONS=detect_leaks=1 "build-fuzz/fuzz/fuzz_$h" -max_total_time="$SECONDS_EACH" \
      -timeout=10 -rss_limit_mb=4096 -print_final_stats=1 -max_len=65536 -artifact_prefix="build-fuzz/findings/$h-" \
      "build-fuzz/corpus/$h" "fuzz/corpus/$h" >"$log" 2>&1; then
    result="no finding"
  else
    result="FINDING (see $log and build-fuzz/findings/)"
    status=1
  fi
  execs=$(grep -Eo 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -Eo '[0-9]+$' || true)
  [ -n "$execs" ] || execs=$(grep -Eo '^#[0-9]+' "$log" | tail -1 | tr -d '#')
  printf 'fuzz %-8s %4ss  executions %10s  %s\n' "$h" "$SECONDS_EACH" "${execs:-?}" "$result"
done
exit $status
