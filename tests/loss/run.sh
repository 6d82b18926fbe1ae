#!/usr/bin/env bash
# Loss assessment as pelicun meets it: a demand sample written by `windmeta demands` (a metamodel
# of 12 experiments, 50 storms at 40 m/s) is loaded with pelicun's own reader (pinned) and its
# values compared with the file's, column by column and storm by storm (tests/loss/check_demands.py).
#
#   bash tests/loss/run.sh            # from the repository's root, after the release build
set -euo pipefail
cd "$(dirname "$0")/../.."
PELICUN_VERSION=3.10.0
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/windmeta/target}"
venv="$HOME/.cache/windmeta/pelicun-venv"
if ! "$venv/bin/python" -c "import pelicun, sys; sys.exit(pelicun.__version__ != '$PELICUN_VERSION')" 2>/dev/null; then
    rm -rf "$venv"
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet "pelicun==$PELICUN_VERSION"
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
windmeta="$CARGO_TARGET_DIR/release/windmeta"
"$windmeta" calibrate --preset frame40-kn --experiments 12 --seed 1 --out "$work/model.json" >/dev/null
"$windmeta" demands --model "$work/model.json" --wind-speed 40 --samples 50 --seed 2 --out "$work/demands.csv"
"$venv/bin/python" tests/loss/check_demands.py "$work/demands.csv" 40
