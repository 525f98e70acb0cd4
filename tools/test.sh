#!/usr/bin/env bash
# The whole test suite: formatting and lints, the Rust tests, then the Python side (fixture
# checks with trimesh and tools/validate.py over every fixture) in a virtual environment
# created from tools/requirements.txt.
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== virtual environment"
tools/venv.sh

echo "== cargo fmt / clippy"
cargo fmt --all -- --check
cargo clippy --release --all-targets --locked -- -D warnings

echo "== cargo test"
cargo build --release --locked
cargo test --release --locked

echo "== python tests"
.venv/bin/python -m pytest tests/python -q

echo "== validation against trimesh and the quadric reference"
.venv/bin/python tools/raycast_tools/validate.py fixtures
