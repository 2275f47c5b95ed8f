#!/usr/bin/env bash
# The fan-out client against one request: a 3840×2160 render of
# examples/spheres.json at 16 samples, through 1, 2 and 3 replicas behind
# HAProxy (deploy/local/cluster.sh), each replica given one worker thread
# (--threads 1), so that a replica stands for one machine's worth of CPU.
#
#   bash benches/fanout.sh            # writes docs/fanout.md
#   ROUNDS=3 TILES=8x8 bash benches/fanout.sh
#
# For each count of replicas, in turns (ROUNDS times): the image in one
# request, sent straight to a replica, then the same image by
# `glint render --via` through HAProxy as TILES tiles, 2 per replica in
# flight. Both PNGs must be the same bytes. Times are wall-clock; CPU is the
# user and system time of every replica, HAProxy and the client over the
# run, from /proc. Ratios are of medians from the same run: the machine's
# speed drifts between runs, and ratios within one are what that leaves
# alone.
set -euo pipefail
cd "$(dirname "$0")/.."

rounds="${ROUNDS:-1}"
tiles="${TILES:-8x8}"
out="docs/fanout.md"

cargo build --release --locked --bin glint >&2
glint="$PWD/target/release/glint"
work="$(mktemp -d)"
cluster_pid=""
cleanup() {
    if [[ -n "$cluster_pid" ]]; then
        kill -TERM "$cluster_pid" 2>/dev/null || true
        wait "$cluster_pid" 2>/dev/null || true
    fi
    rm -rf "$work"
}
trap cleanup EXIT

python3 - "$work/request.json" <<'EOF'
import json, sys
request = json.load(open("examples/spheres.json"))
request["camera"]["width"], request["camera"]["height"] = 3840, 2160
request["samples"] = 16
json.dump(request, open(sys.argv[1], "w"))
EOF

ticks="$(getconf CLK_TCK)"
# CPU seconds (user + system) of the processes PIDS, so far.
cpu() {
    local total=0 pid t
    for pid in "$@"; do
        # Fields 14 and 15 of /proc/PID/stat, after the command's parentheses.
        t=$(sed 's/^.*) //' "/proc/$pid/stat" | awk '{print $12 + $13}')
        total=$((total + t))
    done
    awk -v t="$total" -v hz="$ticks" 'BEGIN { printf "%.2f", t / hz }'
}
now() { date +%s.%N; }
# The value of an arithmetic expression of decimals.
calc() { awk "BEGIN { print $1 }"; }
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

load_before="$(cut -d' ' -f1 /proc/loadavg)"
rows=()
for replicas in 1 2 3; do
    dir="$work/cluster-$replicas"
    mkdir -p "$dir"
    # Loopback ports the kernel picks: HAProxy's, then the replicas'.
    ports=($(python3 -c "import socket
socks = [socket.socket() for _ in range($replicas + 1)]
for s in socks: s.bind(('127.0.0.1', 0))
print(' '.join(str(s.getsockname()[1]) for s in socks))"))
    port=${ports[0]}
    replica_ports=$(IFS=,; echo "${ports[*]:1}")
    bash deploy/local/cluster.sh --port "$port" --replica-ports "$replica_ports" --glint "$glint" \
        --dir "$dir" --drain-ms 0 -- --threads 1 --request-timeout-ms 1800000 \
        >"$dir/out" 2>"$dir/err" &
    cluster_pid=$!
    for ((i = 0; i < 600; i++)); do
        grep -q "glint cluster ready" "$dir/out" 2>/dev/null && break
        sleep 0.1
    done
    grep -q "glint cluster ready" "$dir/out" || { cat "$dir/err" >&2; exit 1; }
    pids=($(cat "$dir"/replica-*.pid "$dir/haproxy.pid"))

    : >"$work/one-s"; : >"$work/one-cpu"; : >"$work/fan-s"; : >"$work/fan-cpu"
    for ((round = 1; round <= rounds; round++)); do
        # One request, straight to the first replica.
        c0=$(cpu "${pids[@]}"); t0=$(now)
        curl -sSf -o "$work/one.png" -H 'content-type: application/json' \
            --data-binary @"$work/request.json" "http://127.0.0.1:${ports[1]}/v1/render"
        t1=$(now); c1=$(cpu "${pids[@]}")
        calc "$t1 - $t0" >>"$work/one-s"
        calc "$c1 - $c0" >>"$work/one-cpu"

        # The fan-out through HAProxy; the client's own CPU from time(1).
        c0=$(cpu "${pids[@]}"); t0=$(now)
        /usr/bin/time -f "%U %S" -o "$work/client-time" \
            "$glint" render "$work/request.json" --via "http://127.0.0.1:$port" \
            --tiles "$tiles" --parallel $((2 * replicas)) -o "$work/fan.png"
        t1=$(now); c1=$(cpu "${pids[@]}")
        client=$(awk '{print $1 + $2}' "$work/client-time")
        calc "$t1 - $t0" >>"$work/fan-s"
        calc "$c1 - $c0 + $client" >>"$work/fan-cpu"
        cmp -s "$work/one.png" "$work/fan.png" || {
            echo "fanout.sh: the fan-out's PNG differs from the one request's" >&2
            exit 1
        }
        echo "replicas $replicas, round $round: one $(tail -1 "$work/one-s") s, fan-out $(tail -1 "$work/fan-s") s" >&2
    done
    one=$(median <"$work/one-s"); fan=$(median <"$work/fan-s")
    one_cpu=$(median <"$work/one-cpu"); fan_cpu=$(median <"$work/fan-cpu")
    rows+=("$(awk -v r="$replicas" -v o="$one" -v f="$fan" -v oc="$one_cpu" -v fc="$fan_cpu" 'BEGIN {
        printf "| %d | %.1f s | %.1f s | %.2f× | %.1f s | %.1f s | %+.1f%% |", r, o, f, o / f, oc, fc, 100 * (fc / oc - 1) }')")

    kill -TERM "$cluster_pid"
    wait "$cluster_pid" || true
    cluster_pid=""
done

load_after="$(cut -d' ' -f1 /proc/loadavg)"
{
    echo "# The fan-out client against one request"
    echo
    echo "Written by \`bash benches/fanout.sh\` (ROUNDS=$rounds, TILES=$tiles) on $(nproc) cores"
    echo "($(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //'))."
    echo
    echo "A 3840×2160 render of \`examples/spheres.json\` at 16 samples per pixel, with"
    echo "its shadows: in one request, sent straight to one replica, and by"
    echo "\`glint render --via\` through HAProxy as $tiles tiles, two per replica in flight."
    echo "Each replica has one worker thread (\`--threads 1\`), standing for one"
    echo "machine's worth of CPU. The two PNGs are the same bytes in every round."
    echo "Times are medians of $rounds round(s), the two measured in turns; CPU is the"
    echo "user and system time of the replicas, HAProxy and the client."
    echo "The machine's load average (1 minute) was $load_before at the start and"
    echo "$load_after at the end: above $(nproc), other work shared the cores, and the"
    echo "times (not the CPU) show it."
    echo
    echo "| replicas | one request | fan-out | fan-out's throughput ÷ one request's | CPU, one request | CPU, fan-out | tile overhead |"
    echo "| --- | --- | --- | --- | --- | --- | --- |"
    printf '%s\n' "${rows[@]}"
    echo
    echo "This machine has $(nproc) cores: past $(nproc) replicas there are no more"
    echo "cores to render on, so a third replica adds nothing but its share of the"
    echo "switching. On machines of their own, each replica adds its CPU."
    echo "The tile overhead is what the fan-out costs beyond the one request:"
    echo "each tile's request parsed and its scene and BVH built again, each tile's"
    echo "PNG encoded by its replica and decoded by the client, and the whole image"
    echo "encoded once more by the client."
} >"$out"
cat "$out"
