#!/usr/bin/env bash
# The whole test suite: formatting and lints (Rust, and Python with ruff), the Rust tests, then
# the Python side (fixture checks with trimesh, and `python -m raycast_tools validate` over every
# fixture) in the virtual environment tools/venv.sh creates from tools/requirements.txt.
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== virtual environment"
tools/venv.sh

echo "== ruff check / ruff format --check (ruff.toml)"
.venv/bin/ruff check
.venv/bin/ruff format --check

echo "== cargo fmt / clippy (the library, the binary and the Python extension python/)"
cargo fmt --all -- --check
cargo clippy --release --workspace --all-targets --locked -- -D warnings
# The Python extension on its own: raycast-io then builds without its `output` feature, as
# the wheel does (a workspace-wide build turns the feature on for everyone).
cargo clippy --release -p raycast-python --locked -- -D warnings

echo "== cargo test"
cargo build --release --locked
cargo test --release --locked

echo "== python package (pip install ./python: maturin builds the extension into .venv)"
start=$SECONDS
# maturin's build backend runs the `maturin` program of the environment: put it on PATH.
PATH="$PWD/.venv/bin:$PATH" .venv/bin/python -m pip install --quiet --disable-pip-version-check \
    --no-input --no-deps --no-build-isolation --force-reinstall ./python
echo "python package installed in $((SECONDS - start)) s"

echo "== python tests"
.venv/bin/python -m pytest tests/python -q --ignore=tests/python/trimesh_upstream

# trimesh's own ray tests, with raycast's drop-in: a process of their own, because trimesh's
# generic.py turns trimesh's strict mode on for every test of the process it is imported in.
echo "== trimesh's own ray tests (tests/python/trimesh_upstream)"
.venv/bin/python -m pytest tests/python/trimesh_upstream -q

echo "== validation against trimesh and the quadric reference"
.venv/bin/python -m raycast_tools validate fixtures
