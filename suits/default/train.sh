#!/usr/bin/env bash
# Reproduces the trained default suit from the CMU clips committed in suits/default/mocap/:
#   suits/default/train.sh [WORK_DIR]
# 1. renders one synthetic dataset per clip (640x480, 30 fps, subjects and backgrounds from fixed seeds,
#    bundled backgrounds in tests/data/backgrounds) into WORK_DIR (default: a temporary directory);
#    21 clips, about 5,500 frames, about 2.5 minutes on a 2-core machine;
# 2. suitcap-train suit: segmenter tables (20 frames of the first dataset), codebooks, RVM regressor
#    (its training descriptors computed with the new segmenter's masks, as at run time), written into
#    suits/default/;
# 3. suitcap-train limits: joint limits (joint_limits.toml) from the same clips.
set -euo pipefail
cd "$(dirname "$0")/../.."
work="${1:-$(mktemp -d)}"
cargo build --release --workspace
data=()
seed=100
for clip in suits/default/mocap/*.bvh; do
  seed=$((seed + 1))
  name=$(basename "$clip" .bvh)
  ./target/release/suitcap-synth --bvh "$clip" --out "$work/$name" --seed "$seed" --overwrite
  data+=(--data "$work/$name")
done
rm -f suits/default/segmenter.bin suits/default/codebook_*.bin
./target/release/suitcap-train suit --suit suits/default "${data[@]}" --basis 1500
./target/release/suitcap-train limits --suit suits/default --data suits/default/mocap/*.bvh
echo "datasets kept in $work"
