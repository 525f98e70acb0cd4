#!/usr/bin/env bash
# Thread scaling of raycast's octree and of the obvhs BVH2 backend: runs
# `python -m raycast_tools thread-scaling` (tools/raycast_tools/bench/thread_scaling.py, standard
# library only), with the repository's .venv when there is one, else a bare python3 that
# finds the package in tools/. Options as before, from the environment: RAYCAST, OUT,
# BIG_SCENE (a further scene, such as the 1M-triangle one `python -m raycast_tools bench`
# writes), PINNING=1 (the taskset pinning experiment); or pass the command's options.
#
#   tools/thread_scaling.sh   -> reports/device/{machine,scaling,topology}.txt (+ pinning.txt)
set -euo pipefail
cd "$(dirname "$0")/.."
python=.venv/bin/python
[ -x "$python" ] || python=python3
PYTHONPATH="tools${PYTHONPATH:+:$PYTHONPATH}" exec "$python" -m raycast_tools thread-scaling "$@"
