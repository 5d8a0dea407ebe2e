#!/usr/bin/env bash
# Installs what building suitcap needs on a fresh Debian or Ubuntu machine:
#   - a C toolchain and pkg-config (crates with C parts),
#   - libclang-dev (the `v4l` crate generates its V4L2 bindings with bindgen, which needs libclang),
#   - Rust through rustup, if `cargo` is not installed yet.
# Safe to run again: it installs only what is missing.
set -euo pipefail

missing=()
for pkg in build-essential pkg-config libclang-dev; do
  dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
if [ "${#missing[@]}" -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  echo "setup: installing ${missing[*]}" >&2
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null 2>&1 && [ ! -x "$HOME/.cargo/bin/cargo" ]; then
  echo "setup: installing Rust with rustup" >&2
  command -v curl >/dev/null 2>&1 || { sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"; $sudo apt-get install -y -qq curl ca-certificates >/dev/null; }
  curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs | sh -s -- -y --profile minimal >&2
fi
