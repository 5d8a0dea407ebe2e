#!/usr/bin/env bash
# Reproduces the README's body-size figures: `suitcap run --live-cloth` with the shipped default suit on
# the first 12 frames of each sequence in WORK_DIR (the datasets `scripts/eval_pose.sh WORK_DIR`
# renders; the run measures the person's size on the first 10 and cuts the garment for it), the
# estimated height against the rendered figure's standing height (the subject's nominal height
# changed by its limb ratios, which `suitcap run` prints from the dataset's manifest and motion),
# and the mean absolute error, against the standing and against the nominal height; and the body's
# widths (girth × height over the base figure's height, which the garment is cut for) against the
# subject's.
#   scripts/eval_bodysize.sh WORK_DIR
set -euo pipefail
cd "$(dirname "$0")/.."
work="${1:?usage: scripts/eval_bodysize.sh WORK_DIR (the datasets of scripts/eval_pose.sh WORK_DIR)}"
ls "$work"/*/manifest.toml >/dev/null 2>&1 ||
  { echo "eval_bodysize: no datasets in $work (run scripts/eval_pose.sh $work first)" >&2; exit 2; }
cargo build --release --bin suitcap
# The base figure's standing height (src/body.rs BASE_HEIGHT_CM), to which girths are relative.
base_cm=$(sed -n 's/^pub const BASE_HEIGHT_CM: f32 = \([0-9.]*\);/\1/p' src/body.rs)
[ -n "$base_cm" ] || { echo "eval_bodysize: BASE_HEIGHT_CM not found in src/body.rs" >&2; exit 1; }
runs=$(mktemp -d)
for dataset in "$work"/*/; do
  dataset=${dataset%/}
  [ -f "$dataset/manifest.toml" ] || continue
  name=$(basename "$dataset")
  mkdir -p "$runs/$name/frames"
  for frame in $(ls "$dataset/frames" | head -12); do
    ln -s "$(realpath "$dataset/frames/$frame")" "$runs/$name/frames/$frame"
  done
  # The dataset's manifest and motion beside the frames: `suitcap run` then prints the truth.
  ln -s "$(realpath "$dataset/manifest.toml")" "$runs/$name/manifest.toml"
  ln -s "$(realpath "$dataset/motion.bvh")" "$runs/$name/motion.bvh"
  output=$(target/release/suitcap run "$runs/$name/frames" --camera "$dataset/camera.toml" \
    --suit suits/default --out "$runs/$name/out" --live-cloth 2>&1)
  line=$(echo "$output" | grep 'body size measured') ||
    { echo "eval_bodysize: $name: no body size measured" >&2; exit 1; }
  truth=$(echo "$output" | grep 'ground truth (generator') ||
    { echo "eval_bodysize: $name: no ground truth printed" >&2; exit 1; }
  cm=$(echo "$line" | sed -n 's/.*: \([0-9.]*\) cm tall.*/\1/p')
  girth=$(echo "$line" | sed -n 's/.*girth \([0-9.]*\).*/\1/p')
  who=$(echo "$truth" | sed -n 's/.*subject \([^,]*\),.*/\1/p')
  nominal=$(echo "$truth" | sed -n 's/.*nominal height \([0-9.]*\) cm.*/\1/p')
  standing=$(echo "$truth" | sed -n 's/.*standing \([0-9.]*\) cm.*/\1/p')
  true_girth=$(echo "$truth" | sed -n 's/.*girth \([0-9.]*\)$/\1/p')
  echo "$name $who $standing $nominal $cm $girth $true_girth"
# The body parts' radii scale with girth × height / the base figure's height, for the generator's
# subjects (at their nominal height) and for the estimated body alike: what the garment is cut
# for. A subject's limb ratios change its standing height but not its widths.
done | awk -v base="$base_cm" '{ err = ($5 - $3) / $3 * 100; nom = ($5 - $4) / $4 * 100
  width = $6 * $5 / base; true_width = $7 * $4 / base; werr = (width - true_width) / true_width * 100
  sum += (err < 0 ? -err : err); sum_nom += (nom < 0 ? -nom : nom); sum_w += (werr < 0 ? -werr : werr); n++
  printf "%-45s %-7s standing %5.1f cm (nominal %3.0f), estimated %5.0f cm (%+.1f %%; %+.1f %% of nominal), girth %s (subject %s), widths %.3f × the base figure'"'"'s (subject %.3f, %+.1f %%)\n", $1, $2, $3, $4, $5, err, nom, $6, $7, width, true_width, werr }
  END { if (n) printf "mean absolute height error over %d sequences: %.1f %% of the standing height (%.1f %% of the nominal); widths (girth × height scale) %.1f %% off\n", n, sum / n, sum_nom / n, sum_w / n }'
rm -rf "$runs"
