#!/usr/bin/env bash
# Exports folders of a git repository's HEAD into a corpus folder for
# `python -m raycast_tools corpus` (docs/corpus.md), file by file, so that blobs a partial
# mirror lacks (large files) are skipped and counted instead of stopping the export.
#
# Usage: tools/export_corpus.sh GIT_DIR DEST NAME REPOSITORY PATH...
#   writes DEST/NAME/<path> for every file under the PATHs of GIT_DIR's HEAD, and appends
#   "NAME REPOSITORY <commit> <paths>" to DEST/SOURCES and the skipped files to DEST/ABSENT.
#   REPOSITORY names where the mirror came from (e.g. github:assimp/assimp).
set -euo pipefail
[ $# -ge 5 ] || { echo "usage: $0 GIT_DIR DEST NAME REPOSITORY PATH..." >&2; exit 2; }
git_dir=$1 dest=$2 name=$3 origin=$4
shift 4
commit=$(git --git-dir="$git_dir" rev-parse HEAD)
mkdir -p "$dest/$name"
absent=0 written=0
while IFS=$'\t' read -r meta path; do
  read -r _ type blob <<<"$meta"
  [ "$type" = blob ] || continue
  mkdir -p "$dest/$name/$(dirname "$path")"
  if git --git-dir="$git_dir" cat-file blob "$blob" >"$dest/$name/$path" 2>/dev/null; then
    written=$((written + 1))
  else
    rm -f "$dest/$name/$path"
    echo "$name/$path" >>"$dest/ABSENT"
    absent=$((absent + 1))
  fi
done < <(git --git-dir="$git_dir" ls-tree -r HEAD -- "$@")
echo "$name $origin $commit $*" >>"$dest/SOURCES"
echo "export_corpus: $name: $written files written, $absent absent from the mirror"
