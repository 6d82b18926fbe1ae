#!/usr/bin/env bash
# How several replicas on one PostgreSQL database add up. For each replica count it creates a fresh
# database, starts that many `windmeta serve` replicas on it (one worker each, each pinned to one
# core with one rayon thread, so that a replica is a core), then through the first replica times a
# calibration of `frame40-kn` and a certified exceedance curve on the metamodel it made, each from
# its POST until its operation is done. A calibration's structure selection (a task per mode),
# experiments and expansions, and an answer's metamodel storms and reference storms, are leased
# tasks that every replica's idle workers take, so these times should fall as replicas are added
# (what is left in the job itself: the selection experiments and the plan's assembly). Prints a
# Markdown table on standard output (progress on standard error) and, with --json, writes the same
# as JSON with more detail. Stops every replica it started and drops every database it made, on
# success, on failure and on Ctrl-C.
#
# Needs a release build of windmeta, PostgreSQL at 127.0.0.1:5432 with trust authentication for
# the user postgres or root, psql, taskset, curl and python3.
#
#   bash scripts/replicas.sh --json replicas.json   # the paper's size: K = 200 storms of 900 s,
#                                                   # 10 000 samples with 200 reference storms
#   bash scripts/replicas.sh --replicas "1 2" --experiments 16 --duration 60 \
#       --samples 200 --reference-storms 16          # a few seconds a count
set -euo pipefail

synopsis='usage: scripts/replicas.sh [--binary PATH] [--replicas "1 2 4"] [--experiments K] [--samples N]
                           [--reference-storms R] [--duration SECONDS] [--json FILE]'
usage() {
    echo "$synopsis"
    cat <<'USAGE'
  --binary PATH            windmeta release build
                           (default: ${CARGO_TARGET_DIR:-$HOME/.cache/windmeta/target}/release/windmeta)
  --replicas "1 2 4"       replica counts to measure, in order; speed-ups are over the first
  --experiments K          calibration experiments (default 200, the paper's)
  --samples N              storms of the certified exceedance curve (default 10000)
  --reference-storms R     its reference storms (default 200; at most N)
  --duration SECONDS       storm length of the calibration, and so of the certified answer's
                           reference storms (default: the preset's, 900 s)
  --json FILE              also write the results as JSON to FILE
USAGE
}

binary="${CARGO_TARGET_DIR:-$HOME/.cache/windmeta/target}/release/windmeta"
counts="1 2 4"
experiments=200
samples=10000
reference_storms=200
duration=""
json=""
preset=frame40-kn

bad_usage() {
    echo "replicas.sh: $1" >&2
    echo "$synopsis (--help: what each means)" >&2
    exit 2
}
# `positive_integer OPTION VALUE`
positive_integer() {
    [[ $2 =~ ^[1-9][0-9]*$ ]] || bad_usage "$1 takes a positive integer, not '$2'"
}

while (($#)); do
    case $1 in
        -h | --help) usage; exit 0 ;;
        --binary | --replicas | --experiments | --samples | --reference-storms | --duration | --json)
            (($# >= 2)) || bad_usage "$1 needs a value"
            case $1 in
                --binary) binary=$2 ;;
                --replicas) counts=${2//,/ } ;;
                --experiments) positive_integer "$1" "$2"; experiments=$2 ;;
                --samples) positive_integer "$1" "$2"; samples=$2 ;;
                --reference-storms) positive_integer "$1" "$2"; reference_storms=$2 ;;
                --duration)
                    [[ $2 =~ ^[0-9]*\.?[0-9]+$ && ! $2 =~ ^[0.]+$ ]] ||
                        bad_usage "--duration takes a positive number of seconds, not '$2'"
                    duration=$2 ;;
                --json) json=$2 ;;
            esac
            shift 2 ;;
        *) bad_usage "unknown option '$1'" ;;
    esac
done
read -r -a counts <<<"$counts"
((${#counts[@]})) || bad_usage "--replicas needs at least one count"
for count in "${counts[@]}"; do positive_integer --replicas "$count"; done
((reference_storms <= samples)) ||
    bad_usage "--reference-storms ($reference_storms) may not exceed --samples ($samples)"
[[ -z $json || -d $(dirname "$json") ]] || bad_usage "--json: no directory $(dirname "$json")"

if [[ ! -x $binary ]]; then
    echo "replicas.sh: no windmeta binary at $binary;" \
        "build it with 'cargo build --release' (or give --binary PATH)" >&2
    exit 2
fi
for tool in curl psql python3 taskset; do
    command -v "$tool" >/dev/null || { echo "replicas.sh: needs $tool" >&2; exit 2; }
done

fail() {
    echo "replicas.sh: $1" >&2
    exit 1
}
step() {
    echo "--- $1 (at ${SECONDS} s)" >&2
}
# The cores this script may use (its own affinity, which may be fewer than the machine's).
read -r -a cores <<<"$(python3 -c 'import os; print(*sorted(os.sched_getaffinity(0)))')"
read -r load _ </proc/loadavg

pg_user=""
for user in postgres root; do
    if psql -h 127.0.0.1 -p 5432 -U "$user" -d postgres -Atqc 'SELECT 1' >/dev/null 2>&1; then
        pg_user=$user
        break
    fi
done
[[ -n $pg_user ]] ||
    fail "cannot reach PostgreSQL at 127.0.0.1:5432 as postgres or root (trust authentication)"
sql() {
    psql -h 127.0.0.1 -p 5432 -U "$pg_user" -d postgres -Atq -v ON_ERROR_STOP=1 -c "$1"
}

work=$(mktemp -d)
pids=()
database=""
base=""
follower=""

stop_replicas() {
    local alive pid
    ((${#pids[@]})) || return 0
    kill -TERM "${pids[@]}" 2>/dev/null || true
    # SIGTERM gives back their leases and drains them; give them a while before SIGKILL.
    for _ in $(seq 150); do
        alive=0
        for pid in "${pids[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
        ((alive)) || break
        sleep 0.1
    done
    kill -KILL "${pids[@]}" 2>/dev/null || true
    for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
    pids=()
}
drop_database() {
    [[ -n $database ]] || return 0
    # FORCE: a replica killed a moment ago may still hold a connection the server has not closed.
    sql "DROP DATABASE IF EXISTS $database WITH (FORCE)" ||
        echo "replicas.sh: could not drop database $database" >&2
    database=""
}
finish() {
    status=$?
    set +e
    [[ -z $follower ]] || kill "$follower" 2>/dev/null
    if ((status == 130 || status == 143)); then
        echo "replicas.sh: interrupted; stopping the replicas" >&2
    elif ((status != 0)); then
        for log in "$work"/replica-*.log; do
            [[ -e $log ]] || continue
            echo "--- the last lines of ${log##*/}" >&2
            tail -n 20 "$log" >&2
        done
    fi
    stop_replicas
    drop_database
    rm -rf "$work"
    exit "$status"
}
trap finish EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# `start_replica INDEX COUNT` starts replica INDEX (from 0) of COUNT on core INDEX mod the cores,
# on a free port it reads from the log, and waits until it is ready (its database reachable).
start_replica() {
    local core=${cores[$(($1 % ${#cores[@]}))]} log="$work/replica-$2-$1.log" address=""
    : >"$log"   # before the replica opens it, so that the wait below can read it at once
    DATABASE_URL="postgres://$pg_user@127.0.0.1:5432/$database" RAYON_NUM_THREADS=1 \
        taskset -c "$core" "$binary" serve --listen 127.0.0.1:0 --workers 1 --log-format text >"$log" 2>&1 &
    pids+=("$!")
    for _ in $(seq 300); do
        kill -0 "${pids[-1]}" 2>/dev/null || fail "replica $1 of $2 exited at start"
        address=$(grep -o 'address=127.0.0.1:[0-9]*' "$log" | head -n 1 | cut -d= -f2 || true)
        if [[ -n $address ]] && curl -fs "http://$address/readyz" >/dev/null; then
            echo "replica $1 on core $core at $address" >&2
            [[ -n $base ]] || base="http://$address"
            return
        fi
        sleep 0.1
    done
    fail "replica $1 of $2 was not ready after 30 s"
}

# `api METHOD PATH [BODY]` prints the answer's body, and fails (having printed it) on a status
# other than 2xx; callers report the body.
api() {
    curl --silent --show-error --fail-with-body -X "$1" "$base$2" \
        -H 'content-type: application/json' ${3:+--data "$3"}
}
# `field a.b` prints a (dotted) field of the JSON on standard input; objects and arrays as JSON.
field() {
    python3 -c '
import json, sys
value = json.load(sys.stdin)
for key in sys.argv[1].split("."):
    value = value[key]
print(json.dumps(value) if isinstance(value, (dict, list)) else value)' "$1"
}
now_us() {
    echo "${EPOCHREALTIME//[^0-9]/}"
}

# `timed_operation WHAT PATH BODY` POSTs BODY to PATH through the first replica, follows the
# operation it starts until it is done and sets `operation` (its last state, as JSON), `seconds`
# (POST to done as the operation records them) and `observed` (the same as the client saw it); it
# fails unless the operation succeeded.
timed_operation() {
    local started answer id state elapsed created finished
    started=$(now_us)
    answer=$(api POST "$2" "$3") || fail "the $1 was refused: $answer"
    id=$(field id <<<"$answer" 2>/dev/null) || fail "the $1 did not start an operation: $answer"
    # The event stream sends the operation at every change and ends once it is done: one idle
    # connection, where polling would spend the measured cores on curl and python. Followed in the
    # background so that a SIGTERM to this script is handled at once, not when the stream ends.
    curl --silent --show-error --fail-with-body --no-buffer "$base/v1/operations/$id/events" >"$work/events" &
    follower=$!
    wait "$follower" || fail "following the $1 failed: $(cat "$work/events")"
    follower=""
    elapsed=$(($(now_us) - started))
    printf -v observed '%d.%03d' $((elapsed / 1000000)) $((elapsed % 1000000 / 1000))
    operation=$(sed -n 's/^data: //p' "$work/events" | tail -n 1)
    state=$(field state <<<"$operation")
    [[ $state == succeeded ]] || fail "the $1 ended $state: $operation"
    # The stream reads the operation every 500 ms, so the client sees it done up to that late; its
    # record (created at the POST, finished when done, both on this host's clock) is exact.
    created=$(field created_at_ms <<<"$operation")
    finished=$(field finished_at_ms <<<"$operation")
    printf -v seconds '%d.%03d' $(((finished - created) / 1000)) $(((finished - created) % 1000))
}

# `measure COUNT` times both requests with COUNT replicas and appends a row to $work/rows.
measure() {
    local count=$1 index calibration calibration_observed metamodel stages
    database="windmeta_replicas_${count}_$$"
    step "$count replica(s) on database $database"
    sql "CREATE DATABASE $database" || fail "could not create database $database"
    base=""
    for ((index = 0; index < count; index++)); do start_replica "$index" "$count"; done
    # The storm length the calibration uses, for the report.
    storm_seconds=${duration:-$(api GET "/v1/presets/$preset" | field default_calibration.duration_s)}

    step "calibration of $preset, K = $experiments"
    timed_operation calibration /v1/calibrations \
        "{\"preset\": \"$preset\", \"experiments\": $experiments, \"seed\": 1${duration:+, \"duration_s\": $duration}}"
    calibration=$seconds calibration_observed=$observed
    metamodel=$(field metamodel_id <<<"$operation")
    echo "$calibration s: metamodel $metamodel" >&2
    # The calibration's stages as the metamodel records them, for the JSON: its structure selection
    # runs in the job alone, its coefficients are the experiments spread over the replicas.
    stages=$(api GET "/v1/metamodels/$metamodel" | field calibration.seconds)

    step "certified exceedance curve: $samples samples, $reference_storms reference storms"
    timed_operation "certified exceedance curve" "/v1/metamodels/$metamodel/exceedance" \
        "{\"samples\": $samples, \"seed\": 1, \"certify\": {\"reference_storms\": $reference_storms}}"
    echo "$seconds s" >&2

    printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$count" "$calibration" "$calibration_observed" \
        "$seconds" "$observed" "$stages" >>"$work/rows"
    stop_replicas
    drop_database
}

step "windmeta $("$binary" --version | cut -d' ' -f2) on cores ${cores[*]}; PostgreSQL as $pg_user"
if python3 -c 'import sys; sys.exit(float(sys.argv[1]) < 0.5)' "$load"; then
    echo "replicas.sh: the machine is busy (load average $load): these times will be longer and noisier" >&2
fi
for count in "${counts[@]}"; do measure "$count"; done
step "done"
python3 - "$work/rows" "$json" "${#cores[@]}" "$load" "$preset" "$experiments" "$storm_seconds" "$samples" \
    "$reference_storms" "$("$binary" --version)" <<'REPORT'
import json, sys

rows_file, json_file, cores, load, preset, experiments, duration, samples, reference_storms, version = sys.argv[1:]
cores = int(cores)
cpu = next((line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name")),
           "unknown")
runs = []
for row in open(rows_file).read().splitlines():
    count, calibration, calibration_observed, certified, certified_observed, stages = row.split("\t")
    runs.append({
        "replicas": int(count),
        "cores": min(int(count), cores),
        "calibration_s": float(calibration),
        "calibration_observed_s": float(calibration_observed),
        "calibration_stages_s": json.loads(stages),
        "certified_s": float(certified),
        "certified_observed_s": float(certified_observed),
    })
base = runs[0]
for run in runs:
    run["calibration_speedup"] = round(base["calibration_s"] / run["calibration_s"], 2)
    run["certified_speedup"] = round(base["certified_s"] / run["certified_s"], 2)


def cores_used(run):
    if run["replicas"] <= cores:
        return str(run["cores"])
    most = -(-run["replicas"] // cores)
    if run["replicas"] % cores == 0:
        return f"{cores} ({most} replicas share each core)"
    return f"{cores} (up to {most} replicas share a core)"


print(f"{version}, {cpu}, {cores} cores (load average {load} at the start); one worker and one rayon thread "
      "per replica, each pinned to one core.")
print(f"Calibration of `{preset}`: K = {experiments} storms of {float(duration):g} s. Certified exceedance curve: "
      f"{samples} samples, {reference_storms} reference storms.")
print("Seconds from POST to done as the operation records them, through the first replica.")
print()
print(f"| replicas | cores used | calibration (s) | speed-up over {base['replicas']} "
      f"| certified answer (s) | speed-up over {base['replicas']} |")
print("|---:|---:|---:|---:|---:|---:|")
for run in runs:
    print(f"| {run['replicas']} | {cores_used(run)} | {run['calibration_s']:.2f} | {run['calibration_speedup']:.2f} "
          f"| {run['certified_s']:.2f} | {run['certified_speedup']:.2f} |")

if json_file:
    with open(json_file, "w") as out:
        json.dump({
            "windmeta": version, "cpu": cpu, "cores": cores, "load_average_at_start": float(load), "preset": preset,
            "experiments": int(experiments), "duration_s": float(duration),
            "samples": int(samples), "reference_storms": int(reference_storms),
            "baseline_replicas": base["replicas"], "runs": runs,
        }, out, indent=2)
        out.write("\n")
REPORT
