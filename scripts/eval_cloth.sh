#!/usr/bin/env bash
# Reproduces the README's cloth-quality figures: `examples/cloth_quality` on 46 cases, the
# T-shirt and the dress on real CMU motion, live settings unless marked quality:
#   - the cloth benchmark's eight (walk 02_01 and kick 10_03 on subject chidi, 2,000 and 4,000 vertices);
#   - kick 11_01 on subjects chidi, ana and emil;
#   - the jump, dance, demo and kick 11_01 clips on their own skeletons;
#   - punch 02_05 on chidi;
#   - the quality mode on walk 02_01, kick 10_03 and kick 11_01.
# Prints each case's line (worst frame's 95th-percentile strain, largest strain, deepest vertex at
# a frame's end, vertices that tunnelled through the body) and a summary against the targets
# (95th percentile <= 2 %, largest <= 10 %, no vertex deeper than 2 mm).
#   SHARED=../shared scripts/eval_cloth.sh
set -euo pipefail
cd "$(dirname "$0")/.."
shared="${SHARED:-../shared}"
[ -d "$shared/mocap" ] || { echo "eval_cloth: $shared/mocap not found (set SHARED)" >&2; exit 2; }
cargo build --release --example cloth_quality
bin=target/release/examples/cloth_quality
tests=tests/data/mocap
kick11="$shared/mocap/cmu_11_01_kick_ball.bvh"
punch="$shared/mocap/cmu_02_05_punch_strike.bvh"
# One case per line, named "clip/garment/vertices"; the clip's speed lines are dropped.
cases() { grep ' v ' | sed "s/^clip/$1/"; }
{
  "$bin" | cases clip
  for subject in chidi ana emil; do
    CLOTH_SUBJECT=$subject CLOTH_CLIP="$kick11" "$bin" | cases "kick11-$subject"
  done
  for clip in "$tests/synth_13_39_jump_chidi.bvh" "$tests/synth_05_12_dance_dana.bvh" \
    suits/default/demo/640x480/motion.bvh "$kick11"; do
    name=$(basename "$clip" .bvh)
    [ "$name" = motion ] && name=demo
    CLOTH_SUBJECT=motion CLOTH_CLIP="$clip" "$bin" | cases "$name-own"
  done
  CLOTH_CLIP="$punch" "$bin" | cases punch
  CLOTH_MODE=quality "$bin" | cases quality
  CLOTH_MODE=quality CLOTH_CLIP="$kick11" "$bin" | cases quality-kick11
} | awk '
  # Each case line as it comes (not through `tee /dev/stderr`, which reopens a redirected log
  # file and truncates it, so `eval_cloth.sh > log 2>&1` kept the summary alone), then the summary.
  { print; fflush()
    p95 = -1
    for (i = 1; i <= NF; i++) {
      if ($i == "p95" && p95 < 0) p95 = $(i + 1) + 0
      if ($i == "max" && $(i - 1) == "%") largest = $(i + 1) + 0
      if ($i == "pen") pen = $(i + 1) + 0
      if ($i == "tunnelled") { moving += $(i + 1); dressing += $(i + 4) }
    }
    n++
    if (p95 > 2) { over_p95++; which_p95 = which_p95 " " $1 " (" p95 " %)" }
    if (largest > 10) { over_max++; which_max = which_max " " $1 " (" largest " %)" }
    if (p95 > worst_p95) worst_p95 = p95
    if (largest > worst_max) worst_max = largest
    if (pen > deepest) deepest = pen
  }
  END {
    printf "%d cases: worst-frame 95th percentile at most %.2f %% (%d over 2 %%%s), largest strain at most %.2f %% (%d over 10 %%%s), deepest vertex %.2f mm; tunnelled %d vertices in the motions'"'"' frames, %d while the garments were put on\n",
      n, worst_p95, over_p95, which_p95, worst_max, over_max, which_max, deepest, moving, dressing
  }'
