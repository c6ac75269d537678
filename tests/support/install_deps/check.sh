#!/usr/bin/env bash
# scripts/install_deps.sh on a machine where ParaView's Python removed the VTK headers: a stub
# dpkg-query reports python3-paraview installed and libvtk9-dev not, and stubs of apt-get and
# sudo fail the check if the script tries to install anything. The script must refuse, exit
# non-zero, and name the conflict and the command that restores the headers.
set -u
script="$1"
stubs=$(mktemp -d)
trap 'rm -rf "$stubs"' EXIT
cat > "$stubs/dpkg-query" <<'STUB'
#!/usr/bin/env bash
pkg="${!#}"
case "$pkg" in
  libvtk9-dev|python3-vtk9) exit 1 ;;
  *) echo "install ok installed" ;;
esac
STUB
for tool in apt-get sudo; do
  printf '#!/bin/sh\necho "STUB %s called: the script tried to install" >&2\nexit 3\n' "$tool" \
    > "$stubs/$tool"
done
chmod +x "$stubs"/*
out=$(PATH="$stubs:$PATH" bash "$script" 2>&1)
code=$?
echo "$out"
if [ "$code" -eq 0 ]; then echo "FAIL: exit 0"; exit 1; fi
if echo "$out" | grep -q "STUB"; then echo "FAIL: it tried to install"; exit 1; fi
for want in "libvtk9-dev is not installed" "python3-paraview" \
            "sudo apt-get install --no-install-recommends libvtk9-dev python3-vtk9"; do
  if ! echo "$out" | grep -qF -- "$want"; then echo "FAIL: no '$want'"; exit 1; fi
done
echo "install_deps check passed"
