#!/usr/bin/env bash
# Reproduces the README's marker figures: five synthetic 640x480 sequences of motions the default
# suit was not trained on, then recall and precision of `suitcap describe` against the generator's
# visible markers (>= 60 % of the square visible, as the issue counts; then of those also >= 6 px
# visible), inside the ground-truth masks and inside the shipped segmenter's masks, with the
# descriptor's median time per frame.
#   scripts/eval_markers.sh [WORK_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
shared="${SHARED:-../shared}"
work="${1:-$(mktemp -d)}"
[ -d "$shared/mocap" ] || { echo "eval_markers: $shared/mocap not found (set SHARED)" >&2; exit 2; }
cargo build --release --workspace
bin=target/release
gen() { # clip name seed subject
  "$bin/suitcap-synth" --bvh "$1" --out "$work/$2" --seed "$3" --subject "$4" --frames 60 \
    --backgrounds "$shared/backgrounds/photos" --overwrite >/dev/null
}
gen tests/data/mocap/cmu_08_01_walk.bvh walk08 201 ana
gen tests/data/mocap/cmu_10_03_kick_ball.bvh kick10 202 ben
gen tests/data/mocap/cmu_13_39_jump.bvh jump13 203 chidi
gen "$shared/mocap/cmu_05_12_dance_arms_high_torso_rotation.bvh" dance05 204 dana
gen "$shared/mocap/cmu_11_01_kick_ball.bvh" kick11 205 emil
for s in walk08 kick10 jump13 dance05 kick11; do
  d="$work/$s"
  "$bin/suitcap" segment --suit suits/default --input "$d/frames" --out "$d/segmasks" >/dev/null
  for masks in masks segmasks; do
    r=$("$bin/suitcap" describe --suit suits/default --input "$d/frames" --masks "$d/$masks" \
      --out "$d/descriptors_$masks.csv" --markers-out "$d/markers_$masks.csv" --truth-markers "$d/markers.csv")
    echo "$s, $masks: $(echo "$r" | grep -o 'recall.*') | $(echo "$r" | grep -o 'median [0-9.]* ms')"
  done
done
echo "datasets kept in $work"
