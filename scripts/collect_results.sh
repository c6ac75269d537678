#!/usr/bin/env bash
# Copies the small, committable part of a campaign, calibration, `reposetwin paper` or
# `reposetwin loop` output folder into results/: every JSON, TOML, CSV and Markdown file, the page's PNG plots, and each
# run's scene.resolved.toml, but no snapshots, frames or checkpoints (those stay out of git).
# Because a run counts as finished when its result.json exists, copying a collected folder back
# (`cp -r results/paper runs/paper`) lets `reposetwin paper` resume on a new machine with only
# the unfinished runs left to do. The same holds for a loop's cache (tests/experiments/loop/
# loop_cache_test.cpp), as long as no new photograph of a collected pile is asked for (a
# measurement candidate's probe re-photographs existing piles and needs their final.vtp; a
# twin photo for the loop's page that was not taken before is left out, with a note).
#
#   scripts/collect_results.sh runs/paper results/paper
set -euo pipefail

if [[ $# -ne 2 ]]; then
  echo "usage: $0 SOURCE_DIR DEST_DIR" >&2
  exit 2
fi
src=$1
dest=$2
if [[ ! -d "$src" ]]; then
  echo "$0: $src: no such folder" >&2
  exit 2
fi

mkdir -p "$dest"
# A run that has not finished (started.json without result.json) is left out whole: its
# controller record without its checkpoint would only confuse a resume.
unfinished=()
while IFS= read -r -d '' s; do
  d=$(dirname "$s")
  [[ -f "$d/result.json" ]] || unfinished+=(-not -path "$d/*")
done < <(find "$src" -name started.json -print0)
count=0
# Lock files and the run folders' bulk are left behind; a run's own scene.resolved.toml is kept
# because it is the exact input that made the result.
while IFS= read -r -d '' f; do
  rel=${f#"$src"/}
  mkdir -p "$dest/$(dirname "$rel")"
  # Atomic per file: a copy interrupted half-way never leaves a truncated JSON behind.
  cp -p "$f" "$dest/$rel.tmp.$$"
  mv -f "$dest/$rel.tmp.$$" "$dest/$rel"
  count=$((count + 1))
done < <(find "$src" -type f \
  \( -name '*.json' -o -name '*.toml' -o -name '*.csv' -o -name '*.md' -o -name '*.html' \
     -o -path '*/paper_page/*.png' -o -path '*/paper_page/*.gp' \) \
  -not -path '*/frames/*' -not -path '*/checkpoint*' -not -name '.*' "${unfinished[@]}" -print0)

echo "collected $count files from $src into $dest ($(du -sh "$dest" | cut -f1))"
