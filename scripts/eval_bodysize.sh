#!/usr/bin/env bash
# Reproduces the README's body-size figures: `suitcap run --live-cloth` with the shipped default suit on
# the first 12 frames of each sequence in WORK_DIR (the datasets `scripts/eval_pose.sh WORK_DIR`
# renders; the run measures the person's size on the first 10 and cuts the garment for it), the
# estimated height against the generator's subject, and the mean absolute error.
#   scripts/eval_bodysize.sh WORK_DIR
set -euo pipefail
cd "$(dirname "$0")/.."
work="${1:?usage: scripts/eval_bodysize.sh WORK_DIR (the datasets of scripts/eval_pose.sh WORK_DIR)}"
ls "$work"/*/manifest.toml >/dev/null 2>&1 ||
  { echo "eval_bodysize: no datasets in $work (run scripts/eval_pose.sh $work first)" >&2; exit 2; }
cargo build --release --bin suitcap
runs=$(mktemp -d)
for dataset in "$work"/*/; do
  dataset=${dataset%/}
  [ -f "$dataset/manifest.toml" ] || continue
  name=$(basename "$dataset")
  mkdir -p "$runs/$name/frames"
  for frame in $(ls "$dataset/frames" | head -12); do
    ln -s "$(realpath "$dataset/frames/$frame")" "$runs/$name/frames/$frame"
  done
  # The generator's subject: its name and nominal height from the manifest's [subject] table.
  subject=$(sed -n '/^\[subject\]/,/^\[/p' "$dataset/manifest.toml")
  who=$(echo "$subject" | sed -n 's/^name = "\(.*\)"/\1/p')
  true_cm=$(echo "$subject" | sed -n 's/^height_cm = //p')
  line=$(target/release/suitcap run "$runs/$name/frames" --camera "$dataset/camera.toml" \
    --suit suits/default --out "$runs/$name/out" --live-cloth 2>&1 | grep 'body size measured') ||
    { echo "eval_bodysize: $name: no body size measured" >&2; exit 1; }
  cm=$(echo "$line" | sed -n 's/.*: \([0-9.]*\) cm tall.*/\1/p')
  girth=$(echo "$line" | sed -n 's/.*girth \([0-9.]*\).*/\1/p')
  echo "$name $who $true_cm $cm $girth"
done | awk '{ err = ($4 - $3) / $3 * 100; sum += (err < 0 ? -err : err); n++
  printf "%-45s %-7s %5.0f cm, estimated %5.0f cm (%+.1f %%), girth %s\n", $1, $2, $3, $4, err, $5 }
  END { if (n) printf "mean absolute height error over %d sequences: %.1f %%\n", n, sum / n }'
rm -rf "$runs"
