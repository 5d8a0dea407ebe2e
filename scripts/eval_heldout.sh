#!/usr/bin/env bash
# A second draw of the held-out test set: the six test motions of scripts/eval_pose.sh (walk 02_01,
# walk 08_01, kick 10_03, jump 13_39, dance 05_12, kick 11_01) rendered twice more, with seeds
# 701-712 (other subjects, cameras, lighting and moving clutter than eval_pose.sh's 201-206, and
# clear of train.sh's 101-127, 601-627, 1101-1127 and 1601-1627), over the same photographs that no
# training rendering saw (../shared/backgrounds/photos less the bundled ones). Then, for the shipped
# default suit on all twelve: the segmenter's mean and worst-frame IoU per sequence (issue #3),
# marker recall and precision inside the ground-truth masks and inside the segmenter's (issue #4,
# markers with >= 60 % of their square visible), and the joint-angle error (issue #5). The figures
# it prints are what the README's rows quote as the "second draw".
#   scripts/eval_heldout.sh [WORK_DIR]
# Needs ../shared (the CMU clips and photographs beside the repository). About 2 minutes on a 2-core
# machine.
set -euo pipefail
cd "$(dirname "$0")/.."
shared="${SHARED:-../shared}"
work="${1:-$(mktemp -d)}"
[ -d "$shared/mocap" ] || { echo "eval_heldout: $shared/mocap not found (set SHARED)" >&2; exit 2; }
cargo build --release --workspace
bin=target/release
. scripts/unseen_photos.sh
unseen_photos "$work/bg"
names=()
seed=700
for pass in 1 2; do
  for clip in tests/data/mocap/cmu_02_01_walk.bvh tests/data/mocap/cmu_08_01_walk.bvh \
    tests/data/mocap/cmu_10_03_kick_ball.bvh tests/data/mocap/cmu_13_39_jump.bvh \
    "$shared/mocap/cmu_05_12_dance_arms_high_torso_rotation.bvh" "$shared/mocap/cmu_11_01_kick_ball.bvh"; do
    seed=$((seed + 1))
    name="$(basename "$clip" .bvh)_$seed"
    "$bin/suitcap-synth" --bvh "$clip" --out "$work/$name" --seed "$seed" --backgrounds "$work/bg" \
      --overwrite >/dev/null
    names+=("$name")
  done
done
data=()
for name in "${names[@]}"; do
  d="$work/$name"
  data+=(--data "$d")
  background=$(sed -n 's/^backgrounds = \["\(.*\)"\]/\1/p' "$d/manifest.toml")
  echo "$name over $(basename "$background"):"
  "$bin/suitcap" segment --suit suits/default --input "$d/frames" --out "$d/segmasks" \
    --truth "$d/masks" | grep -E 'IoU against' | sed 's/^/  segmenter: /'
  for masks in masks segmasks; do
    r=$("$bin/suitcap" describe --suit suits/default --input "$d/frames" --masks "$d/$masks" \
      --out "$d/descriptors_$masks.csv" --truth-markers "$d/markers.csv")
    echo "  markers in $masks: $(echo "$r" | grep -o 'recall [0-9.]* ([0-9]* of [0-9]*), precision [0-9.]*')"
  done
done
"$bin/suitcap-train" eval --suit suits/default "${data[@]}"
echo "datasets kept in $work"
