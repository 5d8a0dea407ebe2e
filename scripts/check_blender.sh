#!/usr/bin/env bash
# A real BVH reader agrees with ours (issue 5): a BVH that suitcap writes (by default the quick
# start's take.bvh) read back by Blender's own importer through ../shared/peers/blender/, and
# compared joint by joint and frame by frame. Fails when any rotation differs by more than
# 0.001 degrees (geodesic) or the root by more than 0.001 file units. Needs ../shared (or SHARED)
# and Blender: a `blender` binary if there is one, else Blender as a Python module, installed on
# first use into ~/.venv-bpy (pip, about 400 MB; CPython 3.11). Not part of the test suite.
#   scripts/check_blender.sh [FILE.bvh]
set -euo pipefail
cd "$(dirname "$0")/.."
shared="${SHARED:-../shared}"
peer="$shared/peers/blender"
[ -f "$peer/blender_bvh_roundtrip.py" ] ||
  { echo "check_blender: $peer not found (set SHARED)" >&2; exit 2; }
work=$(mktemp -d)
bvh="${1:-}"
if [ -z "$bvh" ]; then
  cargo build --release --bin suitcap
  ./target/release/suitcap demo --suit suits/default --out "$work/demo" >/dev/null
  bvh="$work/demo/take.bvh"
fi
json="$work/blender.json"
if command -v blender >/dev/null; then
  blender -b --factory-startup --python-exit-code 3 --python "$peer/blender_bvh_roundtrip.py" \
    -- "$bvh" --out "$json" >/dev/null
else
  if [ ! -x "$HOME/.venv-bpy/bin/python" ]; then
    python3 -m venv "$HOME/.venv-bpy"
    "$HOME/.venv-bpy/bin/pip" install -q "bpy==4.5.*"
  fi
  "$HOME/.venv-bpy/bin/python" "$peer/blender_bvh_roundtrip.py" "$bvh" --out "$json" >/dev/null
fi
report=$(python3 "$peer/compare_bvh_json.py" "$bvh" "$json")
echo "$report" | grep -E '^(bvh|WORST|FK):'
echo "$report" | awk '/^WORST:/ {
  geodesic = $6; root = $10
  if (geodesic + 0 > 1e-3 || root + 0 > 1e-3) { print "check_blender: Blender reads other angles"; exit 1 }
  print "check_blender: Blender reads the same angles"
}'
