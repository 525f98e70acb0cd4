#!/usr/bin/env bash
# Create or refresh the repo's Python environment at <repo>/.venv from
# tools/requirements.txt, with the tools package (tools/raycast_tools, see
# tools/pyproject.toml) installed editable, so `.venv/bin/python -m raycast_tools`
# runs this checkout's tools. Idempotent: a stamp inside .venv records the hashes of
# the requirements file and of pyproject.toml and the interpreter version; when they
# match and the package imports from this checkout nothing is done, otherwise the
# venv is rebuilt from scratch (so removed pins go away).
#
# Usage: tools/venv.sh            (PYTHON=python3.11 tools/venv.sh to pick the interpreter)
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/.." && pwd)"
venv="$root/.venv"
req="$here/requirements.txt"
project="$here/pyproject.toml"
stamp="$venv/.requirements.stamp"
python="${PYTHON:-python3}"

if ! command -v "$python" >/dev/null 2>&1; then
    echo "venv.sh: $python not found" >&2
    exit 1
fi

pyver="$("$python" -c 'import sys; print("%d.%d.%d" % sys.version_info[:3])')"
want="$(cat "$req" "$project" | sha256sum | cut -d' ' -f1) python-$pyver"

# The package imports, from this checkout (-I: not from the current folder).
installed_here() {
    local found
    found="$("$venv/bin/python" -I -c 'import os, raycast_tools as t; print(os.path.realpath(t.__file__))' \
        2>/dev/null)" || return 1
    [[ "$found" == "$(realpath "$here")/raycast_tools/__init__.py" ]]
}

if [[ -f "$stamp" && -x "$venv/bin/python" && "$(cat "$stamp")" == "$want" ]] && installed_here; then
    echo "venv.sh: $venv is up to date (requirements + pyproject $(cut -c1-12 <<<"$want"), python $pyver)"
    exit 0
fi

start=$SECONDS
if [[ -d "$venv" ]]; then
    echo "venv.sh: requirements, pyproject.toml, python or the tools' path changed; rebuilding $venv"
else
    echo "venv.sh: creating $venv with $python ($pyver)"
fi
"$python" -m venv --clear "$venv"
echo "venv.sh: installing $req"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check --no-input -r "$req"
echo "venv.sh: installing $here/raycast_tools (editable)"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check --no-input \
    --no-deps --no-build-isolation --editable "$here"
"$venv/bin/python" -m pip check
echo "$want" >"$stamp"
echo "venv.sh: done in $((SECONDS - start)) s; use $venv/bin/python"
