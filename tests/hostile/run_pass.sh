#!/usr/bin/env bash
# Runs the hostile pass of docs/threat_model.md (the ctest hostile.HostilePass.*) and writes its
# summary table and every case's row, with provenance, into an output folder:
#
#   tests/hostile/run_pass.sh [BUILD_DIR] [OUT_DIR]
#
# BUILD_DIR defaults to build/ (hostile_tests and reposetwin built there), OUT_DIR to
# results/reliability/. Writes OUT_DIR/hostile_pass_<date>_<commit>.csv (command, case, expected,
# exit, outcome, the three disk faults, seconds, why, message) and .md (the table and how it was
# made), and prints the table. Exits with the test's status: non-zero when any of the six fault
# counts (unclear, silent, hung, crashed, refused valid, data lost, path escape, injection) is
# not 0. It takes about three minutes on two shared cores.
set -u
SRC=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=$(realpath "${1:-$SRC/build}")
OUT=$(realpath -m "${2:-$SRC/results/reliability}")
BIN=$BUILD/tests/hostile_tests
[ -x "$BIN" ] || { echo "run_pass.sh: $BIN is not built (cmake --build $BUILD --target hostile_tests)" >&2; exit 2; }
mkdir -p "$OUT"
COMMIT=$(git -C "$SRC" rev-parse --short HEAD)
DIRTY=$(git -C "$SRC" status --porcelain --untracked-files=no | grep -q . && echo " (with uncommitted changes)")
DATE=$(date -u +%Y-%m-%d)
STEM=$OUT/hostile_pass_${DATE}_${COMMIT}
LOG=$(mktemp)
trap 'rm -f "$LOG"' EXIT
START=$(date -u +%H:%M)
REPOSETWIN_HOSTILE_CSV=$STEM.csv "$BIN" --gtest_filter='HostilePass.*' > "$LOG" 2>&1
STATUS=$?
VERSION=$("$BUILD/apps/reposetwin/reposetwin" --version 2>/dev/null)
{
  echo "# Hostile pass, $DATE, commit $COMMIT$DIRTY"
  echo
  echo "Command: \`tests/hostile/run_pass.sh $BUILD $OUT\` (from the repository root), which runs"
  echo "\`$BIN --gtest_filter=HostilePass.*\` with \`REPOSETWIN_HOSTILE_CSV=$(basename "$STEM").csv\`."
  echo "Binary: reposetwin $VERSION. Started $START UTC; test exit status $STATUS."
  echo "Cases and classes: docs/threat_model.md and tests/hostile/hostile_pass_test.cpp."
  echo
  grep -a -m1 '^Hostile pass:' "$LOG"
  echo
  cat "$STEM.csv.table.md"
} > "$STEM.md"
rm -f "$STEM.csv.table.md"
cat "$STEM.md"
if [ $STATUS -ne 0 ]; then
  echo
  grep -a -A200 '^Faults:' "$LOG" | head -n 60
fi
exit $STATUS
