#!/usr/bin/env bash
# The quick start: set-up included, from a fresh clone.
#   scripts/run.sh demo   renders a short synthetic suit clip from the bundled mocap into out/
#   scripts/run.sh test   runs the whole test suite
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
[ -f "$HOME/.cargo/env" ] && . "$HOME/.cargo/env"

case "${1:-}" in
  demo)
    cargo build --release --workspace
    ./target/release/suitcap-synth --bvh tests/data/mocap/cmu_10_03_kick_ball.bvh --frames 75 \
      --size 640x480 --seed 1 --out out/synth --overwrite
    ./target/release/suitcap check --suit suits/default --data out/synth
    ./target/release/suitcap run out/synth/frames --suit suits/default --out out/pose
    ./target/release/suitcap-train eval --suit suits/default --data out/synth
    echo "frames: out/synth/frames/  ground truth: out/synth/motion.bvh  estimated pose: out/pose/take.bvh"
    ;;
  test)
    # The runtime's integration tests drive the generator binary too: build every binary first.
    cargo build --release --workspace
    cargo test --workspace --release
    ;;
  *)
    echo "usage: scripts/run.sh demo|test" >&2
    exit 2
    ;;
esac
