#!/usr/bin/env bash
# The contract, as clients meet it, against a release build of windmeta on a fresh SQLite file:
#  1. the clients design-office tools generate from openapi/openapi.yaml: a Python client
#     (openapi-python-client) and a TypeScript one (openapi-typescript types, openapi-fetch calls),
#     each generated without a warning and running the README's walkthrough against the server,
#     which asks for an API key (tests/contract/python, tests/contract/typescript);
#  2. schemathesis with every check against the server's own /openapi.json, the metamodel operations
#     on the metamodel the Python walkthrough calibrated; this run is against the API role (jobs are
#     queued, not run, so generated calibrations cost nothing). It fails on any failure reported.
# The generators and schemathesis are pinned; nothing they generate is kept.
#
#   bash tests/contract/run.sh            # from the repository's root; about a minute after the build
set -euo pipefail
cd "$(dirname "$0")/../.."
SCHEMATHESIS_VERSION=4.32.5
PYTHON_CLIENT_GENERATOR_VERSION=0.29.1
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/windmeta/target}"
venv="$HOME/.cache/windmeta/contract-venv"
# CPython 3.11.7's `ast` fails inside Hypothesis's deep generator stacks ("AST constructor
# recursion depth mismatch", a tool error, not a finding); a newer Python where there is one.
python=$(ls -d "$HOME"/.pyenv/versions/3.1[23]*/bin/python3 2>/dev/null | tail -n 1 || true)
python=${python:-python3}
if ! "$venv/bin/st" --version 2>/dev/null | grep -q "$SCHEMATHESIS_VERSION" ||
    ! "$venv/bin/openapi-python-client" --version 2>/dev/null | grep -q "$PYTHON_CLIENT_GENERATOR_VERSION"; then
    rm -rf "$venv"
    "$python" -m venv "$venv"
    "$venv/bin/pip" install --quiet "schemathesis==$SCHEMATHESIS_VERSION" \
        "openapi-python-client==$PYTHON_CLIENT_GENERATOR_VERSION"
fi
# The binary as the integration tests build it (`cargo test` unifies the dev-dependencies' features
# into the crate's, so a plain `cargo build` after it would compile the crate a second time).
cargo test --release --no-run --quiet
work=$(mktemp -d)
server=""
base=""
# `start FLAG...` starts the server on a free port (port 0) and sets `base` to the address it logs.
start() {
    : >"$work/server.log"
    "$CARGO_TARGET_DIR/release/windmeta" serve --listen 127.0.0.1:0 --database-url "sqlite://$work/contract.db" \
        --max-queued-jobs 1000000 "$@" >>"$work/server.log" 2>&1 &
    server=$!
    for _ in $(seq 100); do
        address=$(grep -o 'address=127.0.0.1:[0-9]*' "$work/server.log" | head -n 1 | cut -d= -f2 || true)
        if [[ -n $address ]] && curl -fs "http://$address/healthz" >/dev/null; then
            base="http://$address"
            return
        fi
        sleep 0.1
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

key=$(od -An -N24 -tx1 /dev/urandom | tr -d ' \n')
start --role all --workers 1 --api-keys "$key"

echo "--- the Python client"
PATH="$venv/bin:$PATH" openapi-python-client generate --path openapi/openapi.yaml --meta none --fail-on-warning \
    --output-path "$work/python/windmeta_client" >"$work/python-generator.log" 2>&1 ||
    { cat "$work/python-generator.log" >&2; exit 1; }
metamodel=$(PYTHONPATH="$work/python" "$venv/bin/python" tests/contract/python/walkthrough.py "$base" "$key")
export WINDMETA_METAMODEL=${metamodel##*$'\n'}

echo "--- the TypeScript client"
(
    cd tests/contract/typescript
    npm ci --no-audit --no-fund --silent
    # --default-non-nullable false: request fields with a default stay optional (the generator's
    # default makes every field with a default required).
    npx openapi-typescript ../../../openapi/openapi.yaml --default-non-nullable false \
        --output generated/windmeta.d.ts >"$work/typescript-generator.log" 2>&1
    if grep -iE 'warn|error|⚠' "$work/typescript-generator.log"; then
        echo "openapi-typescript did not take the contract cleanly" >&2
        exit 1
    fi
    npx tsc --project .
    node build/walkthrough.js "$base" "$key"
)
stop

echo "--- schemathesis"
start --role api

SCHEMATHESIS_HOOKS=hooks PYTHONPATH=tests/contract "$venv/bin/st" --config-file tests/contract/schemathesis.toml \
    run "$base/openapi.json" \
    --checks all --max-examples "${CONTRACT_EXAMPLES:-30}" --workers 2 --seed "${CONTRACT_SEED:-1}" \
    --max-response-time 10 "$@"
