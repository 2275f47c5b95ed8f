#!/usr/bin/env bash
# A local glint cluster in one command: N `glint serve` replicas behind
# HAProxy (deploy/haproxy/glint.cfg, which says why HAProxy, and
# deploy/local/haproxy.cfg), each replica restarted when it exits, as an
# orchestrator would.
#
#   deploy/local/cluster.sh [--replicas N] [--port PORT] [--replica-ports P1,P2,…]
#                           [--glint PATH] [--dir DIR] [--drain-ms MS]
#                           [-- FLAGS OF glint serve…]
#
# http://127.0.0.1:PORT is then the cluster (PORT 8080 unless given); the
# replicas listen on PORT+1 … PORT+N unless --replica-ports names theirs, and
# answer with `x-served-by: replica-I`. Ctrl-C or SIGTERM stops it all: each
# replica drains and exits, then HAProxy.
#
# The run directory (--dir, else a new one under $TMPDIR) holds HAProxy's
# configuration, log and stats socket (`echo 'show stat' | socat -
# DIR/haproxy.sock` shows the retries), and for replica I: replica-I.log,
# replica-I.pid (its process now) and replica-I.exits (one exit status a line).
#
# Needs haproxy (Debian: `apt-get install haproxy`). The glint binary is
# --glint, else $GLINT, else this repository's target/release/glint, built
# first if missing.
set -euo pipefail

here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"

replicas=3
port=8080
replica_ports=""
glint="${GLINT:-}"
dir=""
# HAProxy takes a replica out after 2 failed checks 250 ms apart: a second
# of drain leaves it time to see /readyz turn 503.
drain_ms=1000
serve_flags=()

# The header above; on stdout for --help, on stderr for a mistake.
usage() {
    local code="${1:-2}" text
    text="$(sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//')"
    if ((code)); then echo "$text" >&2; else echo "$text"; fi
    exit "$code"
}

while (($#)); do
    case "$1" in
        --replicas) replicas="$2"; shift 2 ;;
        --port) port="$2"; shift 2 ;;
        --replica-ports) replica_ports="$2"; shift 2 ;;
        --glint) glint="$2"; shift 2 ;;
        --dir) dir="$2"; shift 2 ;;
        --drain-ms) drain_ms="$2"; shift 2 ;;
        -h|--help) usage 0 ;;
        --) shift; serve_flags=("$@"); break ;;
        *) echo "cluster.sh: unknown argument $1" >&2; usage ;;
    esac
done

command -v haproxy >/dev/null || {
    echo "cluster.sh: haproxy is not installed (Debian: apt-get install haproxy)" >&2
    exit 1
}
if [[ -z "$glint" ]]; then
    glint="$repo/target/release/glint"
    if [[ ! -x "$glint" ]]; then
        echo "cluster.sh: building $glint" >&2
        (cd "$repo" && cargo build --release --locked --bin glint)
    fi
fi

if [[ -n "$replica_ports" ]]; then
    IFS=, read -r -a ports <<<"$replica_ports"
    replicas=${#ports[@]}
else
    ports=()
    for ((i = 1; i <= replicas; i++)); do ports+=($((port + i))); done
fi
((replicas >= 1)) || { echo "cluster.sh: no replicas" >&2; exit 2; }
dir="${dir:-$(mktemp -d "${TMPDIR:-/tmp}/glint-cluster.XXXXXX")}"
mkdir -p "$dir"
rm -f "$dir"/stopping "$dir"/replica-*.exits "$dir"/replica-*.pid

# Up to 20 s, 0.1 s apart, for URL to answer 200 (glint's own probe).
wait_ready() {
    for ((try = 0; try < 200; try++)); do
        if "$glint" healthcheck --url "$1" 2>/dev/null; then return 0; fi
        sleep 0.1
    done
    return 1
}

# Replica I on PORT, started again each time it exits until the cluster
# stops; its exit statuses go to replica-I.exits.
supervise() {
    local i="$1" port="$2" status
    while [[ ! -e "$dir/stopping" ]]; do
        "$glint" serve --listen "127.0.0.1:$port" --instance-id "replica-$i" \
            --drain-ms "$drain_ms" "${serve_flags[@]}" >>"$dir/replica-$i.log" 2>&1 &
        echo "$!" >"$dir/replica-$i.pid"
        status=0
        wait "$!" || status=$?
        echo "$status" >>"$dir/replica-$i.exits"
        # A pause before the restart, so that a replica that cannot start
        # does not spin.
        [[ -e "$dir/stopping" ]] || sleep 0.2
    done
}

supervisors=()
haproxy_pid=""
stop() {
    trap - TERM INT
    touch "$dir/stopping"
    for ((i = 1; i <= replicas; i++)); do
        [[ -s "$dir/replica-$i.pid" ]] && kill -TERM "$(cat "$dir/replica-$i.pid")" 2>/dev/null || true
    done
    # Each replica drains within its own grace period.
    for pid in "${supervisors[@]}"; do wait "$pid" 2>/dev/null || true; done
    if [[ -n "$haproxy_pid" ]]; then
        kill -USR1 "$haproxy_pid" 2>/dev/null || true
        wait "$haproxy_pid" 2>/dev/null || true
    fi
    echo "glint cluster stopped (run directory $dir)" >&2
    exit "${1:-0}"
}
trap 'stop 0' TERM INT

for ((i = 1; i <= replicas; i++)); do
    supervise "$i" "${ports[$((i - 1))]}" &
    supervisors+=("$!")
done
for ((i = 1; i <= replicas; i++)); do
    if ! wait_ready "http://127.0.0.1:${ports[$((i - 1))]}/readyz"; then
        echo "cluster.sh: replica-$i is not ready; its log:" >&2
        tail -n 20 "$dir/replica-$i.log" >&2 || true
        stop 1
    fi
done

cp "$here/haproxy.cfg" "$dir/haproxy.cfg"
for ((i = 1; i <= replicas; i++)); do
    echo "    server replica-$i 127.0.0.1:${ports[$((i - 1))]}" >>"$dir/haproxy.cfg"
done
export GLINT_RUN_DIR="$dir" GLINT_LB_ADDR="127.0.0.1:$port"
shared="$repo/deploy/haproxy/glint.cfg"
haproxy -c -q -f "$shared" -f "$dir/haproxy.cfg" || stop 1
haproxy -db -f "$shared" -f "$dir/haproxy.cfg" 2>>"$dir/haproxy.log" &
haproxy_pid=$!
echo "$haproxy_pid" >"$dir/haproxy.pid"
if ! wait_ready "http://127.0.0.1:$port/readyz"; then
    echo "cluster.sh: HAProxy does not answer on 127.0.0.1:$port; its log:" >&2
    tail -n 20 "$dir/haproxy.log" >&2 || true
    stop 1
fi

echo "glint cluster ready: http://127.0.0.1:$port, $replicas replicas (run directory $dir)"
# Until a signal, or until HAProxy ends by itself (then everything stops).
status=0
wait "$haproxy_pid" || status=$?
haproxy_pid=""
echo "cluster.sh: HAProxy exited with status $status" >&2
stop 1
