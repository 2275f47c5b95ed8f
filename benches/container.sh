#!/usr/bin/env bash
# What the container costs, measured here, written into docs/deploy.md
# between its "container figures" markers and printed:
#
# - the image's size, as the engine reports it;
# - the time from `podman run` to the first 200 from /readyz through the
#   published port, GLINT_CONTAINER_STARTS times (10), with its median;
# - requests/s of the 3-vertex shade (benches/load.sh's body: the triangle
#   example without a term breakdown) through the container's published
#   loopback port, against the same static binary run on the host with the
#   same number of workers, in turns: each round runs both, starting from a
#   different one, GLINT_CONTAINER_ROUNDS rounds (5) of
#   GLINT_CONTAINER_SECONDS (5) at 16 and at 64 connections; the figures
#   are the medians of the rounds and the ratio container/host.
#
#   benches/container.sh
#
# Builds the image first (docker/build.sh, podman). Needs podman (and the
# settings of docker/containers.conf on hosts like the test machines),
# curl, jq and wrk, which it installs as root with apt-get when missing.
# Traffic goes to 127.0.0.1 only; everything it starts is stopped when it
# exits.
set -euo pipefail

cd "$(dirname "$0")/.."
starts="${GLINT_CONTAINER_STARTS:-10}"
rounds="${GLINT_CONTAINER_ROUNDS:-5}"
seconds="${GLINT_CONTAINER_SECONDS:-5}"
doc=docs/deploy.md
work="$PWD/target/container-bench"
mkdir -p "$work"
export CONTAINERS_CONF="${CONTAINERS_CONF:-$PWD/docker/containers.conf}"
say() { echo "container.sh: $*" >&2; }

for tool in podman curl jq wrk; do
  command -v "$tool" > /dev/null && continue
  if [ "$(id -u)" = 0 ]; then
    say "installing $tool (Debian's package)"
    apt-get update -qq && apt-get install -y -qq "$tool" > /dev/null
  else
    say "needs $tool (apt-get install $tool, as root)"
    exit 1
  fi
done

GLINT_ENGINE=podman docker/build.sh > "$work/build.log" 2>&1 || { cat "$work/build.log" >&2; exit 1; }
version="$(sed -n 's/^version = "\(.*\)"$/\1/p' Cargo.toml | head -n 1)"
image="localhost/glint:$version"
binary="${CARGO_TARGET_DIR:-$PWD/target}/x86_64-unknown-linux-gnu/release/glint"
size=$(podman image inspect "$image" --format '{{.Size}}')

name="glint-bench-$$"
host_pid=""
stop_all() {
  podman rm --force --time 0 "$name" > /dev/null 2>&1 || true
  [ -z "$host_pid" ] || { kill "$host_pid" 2> /dev/null; wait "$host_pid" 2> /dev/null; } || true
}
trap stop_all EXIT
trap 'exit 130' INT TERM

# Waits (at most 30 s, 10 ms apart) until $1 answers 200.
wait_ready() {
  for _ in $(seq 3000); do
    [ "$(curl -s -o /dev/null -w '%{http_code}' "$1")" = 200 ] && return 0
    sleep 0.01
  done
  say "$1 is not ready"
  exit 1
}

# The median of the arguments.
median() { printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2) }'; }

# Starts: the container is run anew each time, its port published on one
# the kernel chose.
startup=()
for i in $(seq "$starts"); do
  podman rm --force --time 0 "$name" > /dev/null 2>&1 || true
  t0=$(date +%s%N)
  podman run -d --name "$name" --publish 127.0.0.1::8080 "$image" > /dev/null 2>&1
  port=$(podman port "$name" 8080/tcp | head -n 1 | cut -d: -f2)
  wait_ready "http://127.0.0.1:$port/readyz"
  t1=$(date +%s%N)
  startup+=("$(awk -v d="$((t1 - t0))" 'BEGIN { printf "%.0f", d / 1e6 }')")
  say "start $i: ${startup[-1]} ms"
done

# The container that serves the load, and the same binary on the host, with
# as many workers as the container has CPUs.
workers=$(nproc)
container_port=$(podman port "$name" 8080/tcp | head -n 1 | cut -d: -f2)
host_port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
GLINT_LOG_FORMAT=json "$binary" serve --listen "127.0.0.1:$host_port" --threads "$workers" > "$work/host.log" 2>&1 &
host_pid=$!
wait_ready "http://127.0.0.1:$host_port/readyz"

body="$work/shade-3.json"
jq -c 'del(.terms)' examples/triangle.json > "$body"
script="$work/post.lua"
cat > "$script" << EOF_LUA
wrk.method = "POST"
wrk.headers["Content-Type"] = "application/json"
wrk.body = io.open("$body", "rb"):read("*a")
EOF_LUA

# One wrk run on port $1 with $2 connections: requests/s; any answer that
# is not 2xx, or any socket error, stops the script.
measure() {
  local out
  out=$(wrk -t 2 -c "$2" -d "${seconds}s" -s "$script" "http://127.0.0.1:$1/v1/shade")
  if grep -q -e 'Non-2xx' -e 'Socket errors' <<< "$out"; then
    say "errors on port $1: $out"
    exit 1
  fi
  awk '/^Requests\/sec:/ { print $2 }' <<< "$out"
}

declare -A rps
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
for round in $(seq "$rounds"); do
  for c in 16 64; do
    order=(container host)
    ((round % 2)) || order=(host container)
    for where in "${order[@]}"; do
      port=$([ "$where" = container ] && echo "$container_port" || echo "$host_port")
      r=$(measure "$port" "$c")
      say "round $round, $where, $c connections: $r requests/s"
      rps[$where/$c]+="$r "
    done
  done
done
load_after=$(cut -d' ' -f1-3 /proc/loadavg)

table="$work/figures.md"
{
  echo "<!-- container figures: written by benches/container.sh -->"
  echo
  echo "| what | figure |"
  echo "| --- | --- |"
  printf '| image size (`podman image inspect`) | %.1f MB (%d bytes) |\n' "$(awk -v s="$size" 'BEGIN { print s / 1e6 }')" "$size"
  printf '| `podman run` to the first 200 from `/readyz`, median of %d | %s ms (all: %s) |\n' \
    "$starts" "$(median "${startup[@]}")" "$(printf '%s ' "${startup[@]}" | sed 's/ $//; s/ /, /g')"
  for c in 16 64; do
    # shellcheck disable=SC2086
    container=$(median ${rps[container/$c]}) host=$(median ${rps[host/$c]})
    printf '| 3-vertex shade, %d connections: container / host (requests/s, medians of %d rounds) | %.0f / %.0f = %.3f |\n' \
      "$c" "$rounds" "$container" "$host" "$(awk -v a="$container" -v b="$host" 'BEGIN { print a / b }')"
  done
  echo
  echo "$workers workers in both, wrk with 2 threads, ${seconds} s a run, in turns. The machine's"
  echo "load average (1, 5, 15 minutes) was $load_before before and $load_after after."
  echo
  echo "<!-- end of container figures -->"
} > "$table"

# The block between the markers of docs/deploy.md, replaced.
awk -v table="$table" '
  /^<!-- container figures/ { while ((getline line < table) > 0) print line; skip = 1; next }
  /^<!-- end of container figures/ { skip = 0; next }
  !skip { print }
' "$doc" > "$work/deploy.md"
mv "$work/deploy.md" "$doc"
cat "$table"
