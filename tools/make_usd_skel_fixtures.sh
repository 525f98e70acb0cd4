#!/usr/bin/env bash
# Remakes fixtures/usd/posed/skel.usda and skel.reference.json (issue 28): the UsdSkel fixture is
# authored with usd-core (pinned in tools/requirements.txt) and posed by usd-core at several time
# codes, by UsdSkel.BakeSkinning on a copy and by usd-core's skinning transforms and influences
# in double precision (tools/raycast_tools/reference/usd_skel_reference.py). tests/it/usd_pose.rs compares
# raycast's skinning with these files.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
"$repo/tools/venv.sh" >/dev/null
cd "$repo"
.venv/bin/python -m raycast_tools usd-skel-reference fixtures/usd/posed
