#!/usr/bin/env bash
# run_tutorial.sh TUTORIAL.md BUILD_DIR SURFACES_DIR: runs every ```sh block of the tutorial,
# in order, as one script with `set -e`, in a scratch copy of the source tree's surfaces/
# beside a `build` link to BUILD_DIR: the commands as a reader types them. Any command that
# fails fails the test, with the block's text and its output.
set -euo pipefail
tutorial=$(readlink -f "$1")
build=$(readlink -f "$2")
surfaces=$(readlink -f "$3")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -r "$surfaces" "$work/surfaces"
ln -s "$build" "$work/build"
script="$work/tutorial.sh"
{
  echo 'set -euo pipefail'
  echo 'set -x'
  awk '/^```sh$/ {inside = 1; next} /^```$/ {inside = 0; next} inside {print}' "$tutorial"
} >"$script"
if ! grep -q . <(awk '/^```sh$/ {n++} END {if (n) print n}' "$tutorial"); then
  echo "run_tutorial: no sh blocks in $tutorial" >&2
  exit 1
fi
cd "$work"
bash "$script"
echo "run_tutorial: every command of $(basename "$tutorial") ran"
