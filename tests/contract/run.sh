#!/usr/bin/env bash
# The contract run: schemathesis (pinned) with every check against a release build of windmeta
# serving its own /openapi.json, on a fresh SQLite file. A small metamodel is calibrated first,
# so that the metamodel operations are exercised on a real one; the run itself is against the API
# role (jobs are queued, not run, so generated calibrations cost nothing). It fails on any failure
# schemathesis reports.
#
#   bash tests/contract/run.sh            # from the repository's root; ~30 s after the build
set -euo pipefail
cd "$(dirname "$0")/../.."
SCHEMATHESIS_VERSION=4.32.5
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/windmeta/target}"
venv="$HOME/.cache/windmeta/contract-venv"
# CPython 3.11.7's `ast` fails inside Hypothesis's deep generator stacks ("AST constructor
# recursion depth mismatch", a tool error, not a finding); a newer Python where there is one.
python=$(ls -d "$HOME"/.pyenv/versions/3.1[23]*/bin/python3 2>/dev/null | tail -n 1 || true)
python=${python:-python3}
if ! "$venv/bin/st" --version 2>/dev/null | grep -q "$SCHEMATHESIS_VERSION"; then
    rm -rf "$venv"
    "$python" -m venv "$venv"
    "$venv/bin/pip" install --quiet "schemathesis==$SCHEMATHESIS_VERSION"
fi
# The binary as the integration tests build it (`cargo test` unifies the dev-dependencies' features
# into the crate's, so a plain `cargo build` after it would compile the crate a second time).
cargo test --release --no-run --quiet
work=$(mktemp -d)
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
base="http://127.0.0.1:$port"
server=""
start() {
    "$CARGO_TARGET_DIR/release/windmeta" serve --listen "127.0.0.1:$port" --database-url "sqlite://$work/contract.db" \
        --max-queued-jobs 1000000 "$@" >>"$work/server.log" 2>&1 &
    server=$!
    for _ in $(seq 50); do
        curl -fs "$base/healthz" >/dev/null && return
        sleep 0.2
    done
    echo "the server did not start:" >&2
    cat "$work/server.log" >&2
    exit 1
}
stop() {
    kill "$server" 2>/dev/null || true
    wait "$server" 2>/dev/null || true
}
trap 'stop; rm -rf "$work"' EXIT

start --role all --workers 1
operation=$(curl -fs -X POST "$base/v1/calibrations" -H 'content-type: application/json' \
    -d '{"experiments": 6, "duration_s": 10, "seed": 2}' | python3 -c 'import json, sys; print(json.load(sys.stdin)["id"])')
for _ in $(seq 300); do
    state=$(curl -fs "$base/v1/operations/$operation" | python3 -c 'import json, sys; print(json.load(sys.stdin)["state"])')
    [[ $state == queued || $state == running ]] || break
    sleep 0.2
done
[[ $state == succeeded ]] || { echo "the calibration ended $state" >&2; exit 1; }
export WINDMETA_METAMODEL=$(curl -fs "$base/v1/operations/$operation" | python3 -c 'import json, sys; print(json.load(sys.stdin)["metamodel_id"])')
stop
start --role api

SCHEMATHESIS_HOOKS=hooks PYTHONPATH=tests/contract "$venv/bin/st" --config-file tests/contract/schemathesis.toml \
    run "$base/openapi.json" \
    --checks all --max-examples "${CONTRACT_EXAMPLES:-30}" --workers 2 --seed "${CONTRACT_SEED:-1}" \
    --max-response-time 10 "$@"
