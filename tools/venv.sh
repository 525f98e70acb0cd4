#!/usr/bin/env bash
# Create or refresh the repo's Python environment at <repo>/.venv from
# tools/requirements.txt. Idempotent: a stamp inside .venv records the hash of
# the requirements file and the interpreter version; when both match nothing is
# done, otherwise the venv is rebuilt from scratch (so removed pins go away).
#
# Usage: tools/venv.sh            (PYTHON=python3.11 tools/venv.sh to pick the interpreter)
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/.." && pwd)"
venv="$root/.venv"
req="$here/requirements.txt"
stamp="$venv/.requirements.stamp"
python="${PYTHON:-python3}"

if ! command -v "$python" >/dev/null 2>&1; then
    echo "venv.sh: $python not found" >&2
    exit 1
fi

pyver="$("$python" -c 'import sys; print("%d.%d.%d" % sys.version_info[:3])')"
want="$(sha256sum "$req" | cut -d' ' -f1) python-$pyver"

if [[ -f "$stamp" && -x "$venv/bin/python" && "$(cat "$stamp")" == "$want" ]]; then
    echo "venv.sh: $venv is up to date (requirements $(cut -c1-12 <<<"$want"), python $pyver)"
    exit 0
fi

start=$SECONDS
if [[ -d "$venv" ]]; then
    echo "venv.sh: requirements or python changed; rebuilding $venv"
else
    echo "venv.sh: creating $venv with $python ($pyver)"
fi
"$python" -m venv --clear "$venv"
echo "venv.sh: installing $req"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check --no-input -r "$req"
"$venv/bin/python" -m pip check
echo "$want" >"$stamp"
echo "venv.sh: done in $((SECONDS - start)) s; use $venv/bin/python"
