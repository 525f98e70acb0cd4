#!/usr/bin/env bash
# Remakes the usd-core references of fixtures/usd/posed/ (issue 28): *.reference.json, what
# usd-core (pinned in tools/requirements.txt) composes from time_samples.usda at several time
# codes and from variants.usda with several variant selections (tools/raycast_tools/
# usd_pose_reference.py). The .usda fixtures are hand-written; tests/it/usd_pose.rs compares
# raycast's reading with these files.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
"$repo/tools/venv.sh" >/dev/null
cd "$repo"
.venv/bin/python -m raycast_tools usd-pose-reference fixtures/usd/posed
