#!/usr/bin/env bash
# The quick start: set-up included, from a fresh clone.
#   scripts/run.sh demo   the bundled clip through the whole pipeline (pose, garment, compositing) into out/demo
#   scripts/run.sh test   runs the whole test suite
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
[ -f "$HOME/.cargo/env" ] && . "$HOME/.cargo/env"

case "${1:-}" in
  demo)
    cargo build --release --workspace
    ./target/release/suitcap demo --suit suits/default --out out/demo
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
