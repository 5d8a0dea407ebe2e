#!/usr/bin/env bash
# Reproduces the README's segmentation figures: tables learned from 20 frames of one synthetic
# sequence (the term weights chosen by the pair search on its last 6 and on 60 frames each of three
# other training sequences in other rooms; the search alone takes about 9.5 minutes on a 2-core
# machine, 1.3 with `--search coordinate` added to the training line, the old search), then mean
# and worst-frame IoU against the generator's masks on five sequences with other motions, subjects
# and backgrounds (the moving video, and photographs with the suit's own hues: fruit, an aloe
# plant, a cat, a painting), all 640x480, 60 frames.
#   scripts/eval_segmenter.sh [WORK_DIR]
# Needs ../shared (the CMU clips and photographs beside the repository) and a release build.
set -euo pipefail
cd "$(dirname "$0")/.."
shared="${SHARED:-../shared}"
work="${1:-$(mktemp -d)}"
[ -d "$shared/mocap" ] || { echo "eval_segmenter: $shared/mocap not found (set SHARED)" >&2; exit 2; }
cargo build --release --workspace
synth=target/release/suitcap-synth
mkdir -p "$work/bg"
# One photograph per background directory, so that each sequence has the one it names.
for photo in opencv_stuff opencv_fruits opencv_aloeL opencv_starry_night skimage_chelsea \
  opencv_home skimage_coffee opencv_basketball1; do
  mkdir -p "$work/bg/$photo"
  src=$(ls "$shared/backgrounds/photos/$photo".* 2>/dev/null | head -1)
  [ -n "$src" ] || { echo "eval_segmenter: no photograph $photo in $shared/backgrounds/photos" >&2; exit 2; }
  ln -sf "$(realpath "$src")" "$work/bg/$photo/"
done
gen() { # clip out seed subject backgrounds
  "$synth" --bvh "$1" --out "$work/$2" --seed "$3" --subject "$4" --backgrounds "$5" --frames 60 --overwrite >/dev/null
}
gen "$shared/mocap/cmu_05_01_walk.bvh" train 300 dana "$work/bg/opencv_stuff"
# Training sequences of other rooms for the weights' search (other motions and photographs than the tests').
gen "$shared/mocap/cmu_06_01_walk.bvh" validate1 311 ben "$work/bg/opencv_home"
gen "$shared/mocap/cmu_05_07_dance_jetes_arabesque_pirouette_turn.bvh" validate2 312 chidi "$work/bg/skimage_coffee"
gen "$shared/mocap/cmu_13_26_direct_traffic_wave.bvh" validate3 313 fumiko "$work/bg/opencv_basketball1"
gen tests/data/mocap/cmu_02_01_walk.bvh t1_walk_video 301 ana "$shared/backgrounds/video"
gen tests/data/mocap/cmu_10_03_kick_ball.bvh t2_kick_fruits 302 chidi "$work/bg/opencv_fruits"
gen tests/data/mocap/cmu_13_39_jump.bvh t3_jump_aloe 303 emil "$work/bg/opencv_aloeL"
gen "$shared/mocap/cmu_05_12_dance_arms_high_torso_rotation.bvh" t4_dance_cat 304 fumiko "$work/bg/skimage_chelsea"
gen tests/data/mocap/cmu_08_01_walk.bvh t5_walk_starry 305 ben "$work/bg/opencv_starry_night"
rm -rf "$work/suit" && cp -r suits/default "$work/suit" && rm -f "$work/suit/segmenter.bin"
target/release/suitcap-train segment --suit "$work/suit" --data "$work/train" --frames 20 \
  --validate "$work/validate1" --validate "$work/validate2" --validate "$work/validate3" | tail -1
for t in t1_walk_video t2_kick_fruits t3_jump_aloe t4_dance_cat t5_walk_starry; do
  echo "$t:"
  target/release/suitcap segment --suit "$work/suit" --input "$work/$t/frames" --out "$work/masks/$t" \
    --truth "$work/$t/masks" | grep -E 'IoU|median'
done
echo "datasets and masks kept in $work"
