#!/usr/bin/env bash
# The end-to-end load benchmark of glint: requests/s and latency percentiles
# of the release server at 1, 16, 64 and 256 connections for a 3-vertex
# shade, a 100k-vertex shade and a 640×480 render, beside the ceilings of
# this machine (benches/echo_server.rs, on the same stack: an axum endpoint
# doing no work, a typed JSON echo of the 3-vertex body, and one that only
# parses the vertices of the 100k-vertex body with serde_json). Writes the
# table to docs/load.md.
#
#   benches/load.sh                        # 5 s per run, about 9 minutes
#   GLINT_LOAD_SECONDS=2 benches/load.sh   # a quick check that it works
#
# Then the load target side by side: the typed JSON echo and the 3-vertex
# shade at 64 connections in alternating runs, with the medians.
#
# Settings (environment): GLINT_LOAD_SECONDS (per run), GLINT_LOAD_CONNECTIONS
# (list), GLINT_LOAD_ROUNDS (of the side-by-side runs, 5), GLINT_LOAD_OUT (the
# markdown file), GLINT_LOAD_NOTE (a line about the conditions of this run,
# written under the table).
#
# Traffic goes to 127.0.0.1 only, every run is bounded in time, and
# everything this script starts is stopped when it exits. oha is installed
# into target/tools the first time (cargo install from crates.io: about 20
# minutes of building on 2 cores).
set -euo pipefail

cd "$(dirname "$0")/.."
seconds="${GLINT_LOAD_SECONDS:-5}"
read -r -a connections <<< "${GLINT_LOAD_CONNECTIONS:-1 16 64 256}"
out="${GLINT_LOAD_OUT:-docs/load.md}"
note="${GLINT_LOAD_NOTE:-}"
tools="$PWD/target/tools"
work="$PWD/target/load"
mkdir -p "$work" "$(dirname "$out")"

started=()
stop_all() {
  for pid in "${started[@]}"; do
    kill "$pid" 2>/dev/null || true
  done
  for pid in "${started[@]}"; do
    wait "$pid" 2>/dev/null || true
  done
}
trap stop_all EXIT
trap 'exit 130' INT TERM

say() { echo "load.sh: $*" >&2; }

command -v jq > /dev/null || { say "needs jq (apt-get install jq)"; exit 1; }
command -v curl > /dev/null || { say "needs curl (apt-get install curl)"; exit 1; }

say "building the release server and the ceiling"
cargo build --release --bin glint
glint="$PWD/target/release/glint"
echo_server=$(cargo bench --bench echo_server --no-run --message-format=json |
  jq -r 'select(.reason == "compiler-artifact" and .target.name == "echo_server") | .executable')
[ -x "$echo_server" ] || { say "no echo_server bench binary"; exit 1; }

if [ ! -x "$tools/bin/oha" ]; then
  say "installing oha into $tools"
  cargo install oha --locked --root "$tools"
fi
oha="$tools/bin/oha"

# The request bodies, made once. The 3-vertex shade is the triangle
# example as a client asks for colours alone (the contract's default of no
# term breakdown); the example itself, with its term summary, is a row of
# its own.
summary="examples/triangle.json"
small="$work/shade-3.json"
jq -c 'del(.terms)' "$summary" > "$small"
big="$work/shade-100k.json"
big_vertices=100000
if [ ! -s "$big" ]; then
  # A bumpy 100k-vertex grid lit by the triangle example's two lights.
  awk -v n="$big_vertices" 'BEGIN {
    side = int(sqrt(n)) + 1
    printf "{\"material\":{\"diffuse\":[0.8,0.2,0.2],\"specular\":[1,1,1],\"shininess\":32},"
    printf "\"lights\":[{\"position\":[1,1,1,0]},"
    printf "{\"position\":[0,2,2,1],\"diffuse\":[0.2,0.2,1.0],\"attenuation\":[1,0.1,0.01]}],"
    printf "\"vertices\":{\"positions\":["
    for (i = 0; i < n; i++) {
      u = (i % side) / side; v = int(i / side) / side
      printf "%s[%.5f,%.5f,%.5f]", (i ? "," : ""), u * 4 - 2, v * 4 - 2, -3 + 0.2 * sin(u * 9)
    }
    printf "],\"normals\":["
    for (i = 0; i < n; i++) {
      u = (i % side) / side; v = int(i / side) / side
      printf "%s[%.5f,%.5f,1]", (i ? "," : ""), 0.5 * sin(u * 7), 0.5 * cos(v * 5)
    }
    printf "]}}\n"
  }' > "$big"
fi
render="$work/render-640x480.json"
if [ -f examples/spheres.json ]; then
  jq -c '.camera.width = 640 | .camera.height = 480' examples/spheres.json > "$render"
else
  render=""
fi

# A free loopback port at or after $1.
free_port() {
  local port=$1
  while (exec 3<> "/dev/tcp/127.0.0.1/$port") 2> /dev/null; do
    port=$((port + 1))
  done
  echo "$port"
}

# Waits (at most 10 s) until $1 answers.
wait_for() {
  for _ in $(seq 100); do
    if curl -s -o /dev/null "$1"; then return 0; fi
    sleep 0.1
  done
  say "$1 did not answer"
  exit 1
}

glint_port=$(free_port 18080)
# Every request is admitted (a queue longer than the most connections), so
# the runs measure throughput and queueing, not load shedding (which the
# tests in tests/load/ prove).
RUST_LOG=warn "$glint" serve --listen "127.0.0.1:$glint_port" --queue 1024 &
started+=($!)
echo_port=$(free_port $((glint_port + 1)))
"$echo_server" --listen "127.0.0.1:$echo_port" &
started+=($!)
wait_for "http://127.0.0.1:$glint_port/readyz"
wait_for "http://127.0.0.1:$echo_port/"

rows=()
declare -A rps_of ok_of

# Milliseconds to two places, or a dash for none.
ms() { if [ "$1" = - ]; then echo "—"; else printf '%.2f' "$1"; fi; }

# measure NAME URL BODY CONNECTIONS: one oha run; prints requests/s, the
# share of 200s, answers, p50, p99, p99.9 (ms) and failures, tab-separated.
# The run sends for $seconds, then waits for the requests still in flight
# (-w; the server answers each within its request timeout), so that slow
# answers count too.
measure() {
  local name=$1 url=$2 body=$3 c=$4
  local json="$work/${name//[^a-z0-9]/_}-$c.json"
  say "$name, $c connections, ${seconds}s"
  "$oha" --no-tui --output-format json -z "${seconds}s" -w -c "$c" -m POST \
    -H 'content-type: application/json' -D "$body" "$url" > "$json"
  jq -r '
    ([.statusCodeDistribution[]] | add // 0) as $answered
    | (.statusCodeDistribution["200"] // 0) as $ok
    | [(if $answered > 0 then $answered / .summary.total else 0 end),
       ($ok / ([$answered, 1] | max)), $answered,
       (.latencyPercentiles | .p50, .p99, .["p99.9"] | if . == null then "-" else . * 1000 end),
       ([.errorDistribution[]] | add // 0)]
    | @tsv' "$json"
}

# run NAME URL BODY CONNECTIONS: one oha run, one table row.
run() {
  local name=$1 c=$4
  local rps ok answered p50 p99 p999 failed
  IFS=$'\t' read -r rps ok answered p50 p99 p999 failed < <(measure "$@")
  rps_of["$name/$c"]=$rps
  ok_of["$name/$c"]=$ok
  local share="—"
  [ "$answered" -gt 0 ] && share=$(printf '%.0f%%' "$(jq -n "$ok * 100")")
  rows+=("$(printf '| %s | %d | %.0f | %s | %s | %s | %s | %d |' "$name" "$c" "$rps" \
    "$(ms "$p50")" "$(ms "$p99")" "$(ms "$p999")" "$share" "$failed")")
}

# workload NAME URL BODY: one run per number of connections.
workload() {
  for c in "${connections[@]}"; do
    run "$1" "$2" "$3" "$c"
  done
}

workload "ceiling (no work)" "http://127.0.0.1:$echo_port/echo" "$small"
workload "ceiling (typed JSON echo)" "http://127.0.0.1:$echo_port/typed" "$small"
workload "shade, 3 vertices" "http://127.0.0.1:$glint_port/v1/shade" "$small"
workload "shade, 3 vertices, term summary" "http://127.0.0.1:$glint_port/v1/shade" "$summary"
workload "parse only, 100k vertices" "http://127.0.0.1:$echo_port/parse" "$big"
workload "shade, 100k vertices" "http://127.0.0.1:$glint_port/v1/shade" "$big"
render_note=""
if [ -n "$render" ]; then
  status=$(curl -s -o /dev/null -w '%{http_code}' -H 'content-type: application/json' \
    --data-binary "@$render" "http://127.0.0.1:$glint_port/v1/render")
  if [ "$status" = 200 ]; then
    workload "render 640×480" "http://127.0.0.1:$glint_port/v1/render" "$render"
  else
    render_note="The 640×480 render was skipped: /v1/render answered $status."
  fi
else
  render_note="The 640×480 render was skipped: there is no examples/spheres.json."
fi

# The load target side by side: the typed JSON echo and the 3-vertex shade
# at 64 connections in turns, so that both meet the same machine (on a
# shared one, its speed drifts between the rows of the table).
rounds="${GLINT_LOAD_ROUNDS:-5}"
[ "$rounds" -ge 1 ] || { say "GLINT_LOAD_ROUNDS must be at least 1"; exit 1; }
pair_rps=() pair_p99=() echo_rps=() echo_p99=() ratios=()
for _ in $(seq "$rounds"); do
  IFS=$'\t' read -r e _ _ _ ep99 _ _ < <(measure "typed echo (side by side)" \
    "http://127.0.0.1:$echo_port/typed" "$small" 64)
  IFS=$'\t' read -r g _ _ _ gp99 _ _ < <(measure "shade, 3 vertices (side by side)" \
    "http://127.0.0.1:$glint_port/v1/shade" "$small" 64)
  echo_rps+=("$e") echo_p99+=("$ep99") pair_rps+=("$g") pair_p99+=("$gp99")
  ratios+=("$(awk -v g="$g" -v e="$e" 'BEGIN { print (e > 0 ? g / e : 0) }')")
done
# The median of the arguments.
median() { printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2) }'; }
side_by_side=$(awk -v n="$rounds" -v s="$seconds" -v g="$(median "${pair_rps[@]}")" -v gp="$(median "${pair_p99[@]}")" \
  -v e="$(median "${echo_rps[@]}")" -v ep="$(median "${echo_p99[@]}")" -v r="$(median "${ratios[@]}")" \
  -v lo="$(printf '%s\n' "${ratios[@]}" | sort -g | head -1)" -v hi="$(printf '%s\n' "${ratios[@]}" | sort -g | tail -1)" \
  'BEGIN { printf "- side by side, %d rounds of %d s each at 64 connections, medians: the 3-vertex shade %.0f requests/s with p99 %.2f ms, the typed JSON echo %.0f requests/s with p99 %.2f ms (the shade at %.0f%% of it); per round, the shade reached %.0f%% of the echo at the median, %.0f%% to %.0f%%", n, s, g, gp, e, ep, (e > 0 ? 100 * g / e : 0), 100 * r, 100 * lo, 100 * hi }')

# The summary lines.
ratio_lines=()
for name in "shade, 3 vertices" "shade, 3 vertices, term summary"; do
  for ceiling in "ceiling (typed JSON echo)" "ceiling (no work)"; do
    if [ -n "${rps_of["$name/64"]:-}" ] && [ -n "${rps_of["$ceiling/64"]:-}" ]; then
      ratio_lines+=("$(awk -v name="$name" -v ceiling="${ceiling#ceiling }" -v g="${rps_of["$name/64"]}" -v e="${rps_of["$ceiling/64"]}" \
        'BEGIN { printf "- %s at 64 connections: %.0f requests/s, %.0f%% of the ceiling %s at %.0f", name, g, (e > 0 ? 100 * g / e : 0), ceiling, e }')")
    fi
  done
done
vertex_lines=()
stream="${rps_of["parse only, 100k vertices/1"]:-0}"
for c in "${connections[@]}"; do
  vertex_lines+=("$(awk -v r="${rps_of["shade, 100k vertices/$c"]}" -v ok="${ok_of["shade, 100k vertices/$c"]}" \
    -v p="${rps_of["parse only, 100k vertices/$c"]}" -v s="$stream" -v n="$big_vertices" -v c="$c" \
    'BEGIN { printf "- 100k-vertex shade at %d connection%s: %.1f million vertices/s end to end, %.0f%% of the parse-only ceiling'"'"'s %.1f at as many connections, %.0f%% of its %.1f on one connection (one serde_json stream)", c, (c == 1 ? "" : "s"), r * ok * n / 1e6, (p > 0 ? 100 * r * ok / p : 0), p * n / 1e6, (s > 0 ? 100 * r * ok / s : 0), s * n / 1e6 }')")
done

dirty=$(git status --porcelain 2> /dev/null | grep -q . && echo ", with uncommitted changes" || true)
{
  echo "# Load benchmark"
  echo
  echo "Written by \`benches/load.sh\`; run it again for current figures. The"
  echo "server is the release build with its defaults except \`--queue 1024\`, so"
  echo "every request is admitted and the runs measure throughput and queueing"
  echo "rather than load shedding (the tests in \`tests/load/\` prove the"
  echo "shedding). Requests/s counts answers of any status per second of the"
  echo "run, its wait for the last answers included; 200s is the share of them"
  echo "that were 200; not answered counts what oha gave up on or could not send."
  echo "Latencies are from the client's side, in milliseconds. The"
  echo "ceilings are \`benches/echo_server.rs\`, axum endpoints on the same stack:"
  echo "\"no work\" reads the 3-vertex body and answers a small JSON without"
  echo "parsing it; \"typed JSON echo\" is axum's \`Json<T>\` in and out, \`T\` the"
  echo "shape of that body (it reads and writes about as much JSON as the shade"
  echo "and does nothing else: the ceiling the load target is set against);"
  echo "\"parse only\" parses the 100k vertices with serde_json into arrays of"
  echo "numbers."
  echo
  echo "- command: \`GLINT_LOAD_SECONDS=$seconds GLINT_LOAD_CONNECTIONS=\"${connections[*]}\" benches/load.sh\`"
  echo "- date: $(date -u '+%Y-%m-%d %H:%M UTC')"
  echo "- commit: $(git rev-parse --short HEAD 2> /dev/null || echo unknown)$dirty"
  echo "- machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//'), $(free -g | awk '/^Mem:/ { print $2 }') GiB"
  echo "- load generator: $("$oha" --version) on the same machine, \`-z ${seconds}s -w\` per run (sends for ${seconds} s, then waits for the answers in flight), no warm-up"
  echo "- bodies: \`examples/triangle.json\` without its \`terms\` (3 vertices, 2 lights, colours only, $(wc -c < "$small") bytes),"
  echo "  and as it is (with a term summary, $(wc -c < "$summary") bytes);"
  echo "  a 100k-vertex grid with the same lights ($(wc -c < "$big") bytes);"
  echo "  \`examples/spheres.json\` at 640×480 (PNG answer)"
  echo
  echo "| workload | connections | requests/s | p50 ms | p99 ms | p99.9 ms | 200s | not answered |"
  echo "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  printf '%s\n' "${rows[@]}"
  echo
  printf '%s\n' "${ratio_lines[@]}"
  echo "$side_by_side"
  printf '%s\n' "${vertex_lines[@]}"
  echo
  echo "Notes:"
  echo
  echo "- The load generator shares the machine's $(nproc) cores with the server,"
  echo "  so every figure here is below what a separate client would measure."
  [ -n "$render_note" ] && echo "- $render_note"
  [ -n "$note" ] && echo "- $note"
  true
} > "$out"
say "wrote $out"
cat "$out"
