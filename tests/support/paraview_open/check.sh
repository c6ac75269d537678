#!/usr/bin/env bash
# scripts/paraview_open.py asked for a screenshot with no display: it must refuse before it loads
# ParaView (so this runs with plain python3, ParaView or not), exit non-zero and give the command
# that renders it, with the run folder and the PNG as typed (quoted where a shell needs it).
set -u
script="$1"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
out=$(cd "$work" && env -u DISPLAY -u WAYLAND_DISPLAY -u REPOSETWIN_PARAVIEW_OFFSCREEN \
      python3 "$script" "my run" --screenshot shot.png 2>&1)
code=$?
echo "$out"
if [ "$code" -eq 0 ]; then echo "FAIL: exit 0"; exit 1; fi
if echo "$out" | grep -q "Traceback"; then echo "FAIL: a traceback"; exit 1; fi
for want in "no display" "xvfb-run -a pvpython scripts/paraview_open.py 'my run' --screenshot shot.png"; do
  if ! echo "$out" | grep -qF -- "$want"; then echo "FAIL: no '$want'"; exit 1; fi
done
echo "paraview_open check passed"
