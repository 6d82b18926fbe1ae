#!/usr/bin/env bash
# The compose deployment end to end: builds the image, starts PostgreSQL and two replicas under a
# project of its own (`windmeta-smoke`, with a generated password and API key), calibrates a small
# metamodel through replica one, follows the operation and reads the metamodel and an exceedance
# curve through replica two, stops replica one in the middle of a second calibration and sees
# replica two finish it, then removes the project and its volume. Needs a Docker engine with
# Compose v2, curl and python3.
#
#   bash docker/smoke.sh          # from anywhere; ports 18080 and 18081 unless SMOKE_PORT_1/2 are set
set -euo pipefail
cd "$(dirname "$0")"
port_1=${SMOKE_PORT_1:-18080}
port_2=${SMOKE_PORT_2:-18081}
env_file=$(mktemp)
key=$(od -An -N24 -tx1 /dev/urandom | tr -d ' \n')
cat > "$env_file" <<VARIABLES
POSTGRES_PASSWORD=$(od -An -N16 -tx1 /dev/urandom | tr -d ' \n')
WINDMETA_API_KEYS=$key
WINDMETA_BIND=127.0.0.1
WINDMETA_PORT_1=$port_1
WINDMETA_PORT_2=$port_2
VARIABLES
compose() {
    docker compose --project-name windmeta-smoke --env-file "$env_file" -f compose.yaml "$@"
}
finish() {
    status=$?
    [[ $status == 0 ]] || compose logs --no-color --tail 40 || true
    compose down --volumes --timeout 30 || true
    rm -f "$env_file"
    exit "$status"
}
trap finish EXIT
step() {
    echo "--- $1 (at ${SECONDS} s)"
}
# `api PORT METHOD PATH [BODY]` prints the answer's body; a status other than 2xx fails the script.
api() {
    curl --silent --show-error --fail-with-body -X "$2" "http://127.0.0.1:$1$3" \
        -H "authorization: Bearer $key" -H 'content-type: application/json' ${4:+--data "$4"}
}
field() {
    python3 -c 'import json, sys; print(json.load(sys.stdin)[sys.argv[1]])' "$1"
}

step "build the image and start PostgreSQL and two replicas"
compose up --build --detach --wait
compose ps --format '{{.Service}}: {{.Status}}'

step "without its key the API refuses"
status=$(curl --silent --output /dev/null --write-out '%{http_code}' "http://127.0.0.1:$port_1/v1/metamodels")
[[ $status == 401 ]] || { echo "expected 401 without a key, got $status" >&2; exit 1; }
echo "401 without a key"

step "calibrate through replica one"
operation=$(api "$port_1" POST /v1/calibrations \
    '{"preset": "frame40-kn", "experiments": 32, "duration_s": 120, "seed": 1}' | field id)
echo "operation $operation"

step "follow it through replica two"
for _ in $(seq 600); do
    state=$(api "$port_2" GET "/v1/operations/$operation" | field state)
    [[ $state == queued || $state == running ]] || break
    sleep 1
done
[[ $state == succeeded ]] || { echo "the calibration ended $state" >&2; api "$port_2" GET "/v1/operations/$operation" >&2; exit 1; }
metamodel=$(api "$port_2" GET "/v1/operations/$operation" | field metamodel_id)
echo "succeeded: metamodel $metamodel"

step "read the metamodel and an exceedance curve through replica two"
api "$port_2" GET "/v1/metamodels/$metamodel" | python3 -c '
import json, sys
m = json.load(sys.stdin)
print("metamodel", sys.argv[1], "(format", m["format"], "version", str(m["version"]) + "):", len(m["models"]), "models")' "$metamodel"
api "$port_2" POST "/v1/metamodels/$metamodel/exceedance" '{"samples": 500, "fixed": {"wind_speed": 35}, "seed": 1}' |
    python3 -c '
import json, sys
c = json.load(sys.stdin)
i = min(range(len(c["probabilities"])), key=lambda i: abs(c["probabilities"][i] - 0.5))
print("roof {} at 35 m/s: P(peak > {:.3f}) = {:.3f} [{:.3f}, {:.3f}] from {} samples".format(
    c["response"]["kind"], c["thresholds"][i], c["probabilities"][i], c["lower"][i], c["upper"][i], c["samples"]))'

step "a replica stopped in the middle of a job gives it back; the other finishes it"
operation=$(api "$port_1" POST /v1/calibrations \
    '{"preset": "frame40-kn", "experiments": 60, "duration_s": 300, "seed": 2}' | field id)
for _ in $(seq 120); do
    state=$(api "$port_2" GET "/v1/operations/$operation" | field state)
    [[ $state == queued ]] || break
    sleep 0.5
done
sleep 2
compose stop replica-1
for _ in $(seq 600); do
    state=$(api "$port_2" GET "/v1/operations/$operation" | field state)
    [[ $state == queued || $state == running ]] || break
    sleep 1
done
[[ $state == succeeded ]] || { echo "the calibration ended $state" >&2; exit 1; }
api "$port_2" GET "/v1/operations/$operation" | python3 -c '
import json, sys
o = json.load(sys.stdin)
print("succeeded after", o["attempts"], "attempts: metamodel", o["metamodel_id"])'
compose start replica-1

step "the jobs' log lines, by replica"
compose logs --no-color replica-1 replica-2 | grep -F 'job{' || true
step "done"
