#!/usr/bin/env bash
# Reproduces the README's pose figures: six synthetic test sequences of motions that are not in the
# default suit's training clips (walk 02_01, walk 08_01, kick 10_03, jump 13_39 from tests/data/mocap;
# dance 05_12 and kick 11_01 from ../shared/mocap), rendered over the photographs of
# ../shared/backgrounds/photos that the repository does not bundle (so no test background was seen in
# training), then `suitcap-train eval` of the shipped default suit on all six at once.
#   scripts/eval_pose.sh [WORK_DIR] [extra suitcap-train eval options, e.g. --truth-masks]
set -euo pipefail
cd "$(dirname "$0")/.."
shared="${SHARED:-../shared}"
work="${1:-$(mktemp -d)}"
shift || true
[ -d "$shared/mocap" ] || { echo "eval_pose: $shared/mocap not found (set SHARED)" >&2; exit 2; }
cargo build --release --workspace
. scripts/unseen_photos.sh
unseen_photos "$work/bg"
data=()
seed=200
for clip in tests/data/mocap/cmu_02_01_walk.bvh tests/data/mocap/cmu_08_01_walk.bvh \
  tests/data/mocap/cmu_10_03_kick_ball.bvh tests/data/mocap/cmu_13_39_jump.bvh \
  "$shared/mocap/cmu_05_12_dance_arms_high_torso_rotation.bvh" "$shared/mocap/cmu_11_01_kick_ball.bvh"; do
  seed=$((seed + 1))
  name=$(basename "$clip" .bvh)
  target/release/suitcap-synth --bvh "$clip" --out "$work/$name" --seed "$seed" --backgrounds "$work/bg" \
    --overwrite >/dev/null
  data+=(--data "$work/$name")
done
target/release/suitcap-train eval --suit suits/default "${data[@]}" "$@"
echo "datasets kept in $work"
