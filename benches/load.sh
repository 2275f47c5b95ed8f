#!/usr/bin/env bash
# The end-to-end load benchmark of glint against its ceiling: a bare axum
# server (benches/bare_axum.rs: no middleware, none of glint's layers) that
# parses the same shade body into typed structs and answers as many colour
# floats. Both run on this machine, and wrk drives them in turns:
#
# - the 3-vertex shade of examples/triangle.json (colours only), at 16 and
#   64 connections: the bare server, glint with its default configuration
#   (access logs on, human lines to a file), glint with JSON lines, and glint
#   with its access line formatted by tracing-subscriber, one run each per
#   round, GLINT_LOAD_ROUNDS rounds; the figures are medians
#   of the rounds, and the ratios are glint's medians over the bare
#   server's (requests/s, and p99 latency);
# - a 100k-vertex shade on one connection, end to end, in turns with the
#   bare server's parse of the same body with serde_json alone: how much
#   longer the serial chain (parse, validate, light, write) takes than its
#   parse;
# - single runs of a few other workloads, for reference.
#
# Writes docs/load.md and prints it.
#
#   benches/load.sh                        # 5 s per run, 5 rounds: about 5 minutes
#   GLINT_LOAD_SECONDS=2 GLINT_LOAD_ROUNDS=3 benches/load.sh   # a quick check
#
# Settings (environment): GLINT_LOAD_SECONDS (per run), GLINT_LOAD_ROUNDS (at
# least 3), GLINT_LOAD_OUT (the markdown file), GLINT_LOAD_NOTE (a line about
# the conditions of this run, written under the table).
#
# Traffic goes to 127.0.0.1 only, every run is bounded in time, and
# everything this script starts is stopped when it exits. wrk is Debian's
# package: the script installs it with apt-get when it is missing and it
# runs as root.
set -euo pipefail

cd "$(dirname "$0")/.."
seconds="${GLINT_LOAD_SECONDS:-5}"
rounds="${GLINT_LOAD_ROUNDS:-5}"
out="${GLINT_LOAD_OUT:-docs/load.md}"
note="${GLINT_LOAD_NOTE:-}"
work="$PWD/target/load"
mkdir -p "$work" "$(dirname "$out")"

say() { echo "load.sh: $*" >&2; }
[ "$rounds" -ge 3 ] || { say "GLINT_LOAD_ROUNDS must be at least 3"; exit 1; }

started=()
stop_all() {
  for pid in "${started[@]}"; do
    kill "$pid" 2> /dev/null || true
  done
  for pid in "${started[@]}"; do
    wait "$pid" 2> /dev/null || true
  done
}
trap stop_all EXIT
trap 'exit 130' INT TERM

for tool in jq curl; do
  command -v "$tool" > /dev/null || { say "needs $tool (apt-get install $tool)"; exit 1; }
done
if ! command -v wrk > /dev/null; then
  if [ "$(id -u)" = 0 ] && command -v apt-get > /dev/null; then
    say "installing wrk (Debian's package)"
    apt-get update -qq && apt-get install -y -qq wrk > /dev/null
  else
    say "needs wrk (apt-get install wrk, as root)"
    exit 1
  fi
fi

say "building the release server and the bare axum server"
cargo build --release --bin glint
glint="$PWD/target/release/glint"
bare=$(cargo bench --bench bare_axum --no-run --message-format=json |
  jq -r 'select(.reason == "compiler-artifact" and .target.name == "bare_axum") | .executable')
[ -x "$bare" ] || { say "no bare_axum bench binary"; exit 1; }

# The request bodies, made once. The 3-vertex shade is the triangle
# example as a client asks for colours alone (the contract's default of no
# term breakdown).
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
render=""
if [ -f examples/spheres.json ]; then
  render="$work/render-640x480.json"
  jq -c '.camera.width = 640 | .camera.height = 480' examples/spheres.json > "$render"
fi

# wrk posts the file named by GLINT_LOAD_BODY and, when done, prints one
# tab-separated line: requests/s, p50, p99 and p99.9 (ms), answers that
# were not 2xx, and socket errors (connect, read, write, timeout).
script="$work/post.lua"
cat > "$script" << 'EOF'
wrk.method = "POST"
wrk.headers["Content-Type"] = "application/json"
local file = assert(io.open(os.getenv("GLINT_LOAD_BODY"), "rb"))
wrk.body = file:read("*a")
file:close()

function done(summary, latency, requests)
  local e = summary.errors
  io.write(string.format("result\t%.1f\t%.3f\t%.3f\t%.3f\t%d\t%d\n",
    summary.requests / (summary.duration / 1e6),
    latency:percentile(50) / 1e3, latency:percentile(99) / 1e3, latency:percentile(99.9) / 1e3,
    e.status, e.connect + e.read + e.write + e.timeout))
end
EOF

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

# The servers: the bare one, and glint with its default configuration in
# each log format, its access log going to a file (as `glint > glint.log`
# would). The log files are emptied before each run, to keep them small.
declare -A port_of pid_of log_of
next_port=18080
start() {
  local name=$1 port
  shift
  port=$(free_port "$next_port")
  next_port=$((port + 1))
  log_of[$name]="$work/$name.log"
  "$@" --listen "127.0.0.1:$port" >> "${log_of[$name]}" 2>&1 &
  started+=($!)
  port_of[$name]=$port pid_of[$name]=$!
}
start bare "$bare"
start human "$glint" serve
start json env GLINT_LOG_FORMAT=json "$glint" serve
# The default configuration with its access line formatted by
# tracing-subscriber, as every other line is: what glint's own formatting
# of that line saves.
start tracing env GLINT_ACCESS_LINE=tracing "$glint" serve
for name in bare human json tracing; do
  wait_for "http://127.0.0.1:${port_of[$name]}/$([ "$name" = bare ] && echo parse || echo healthz)"
done

# The server's CPU time so far (user + system), in clock ticks.
cpu_ticks() { awk '{ print $14 + $15 }' "/proc/$1/stat"; }
ticks_per_second=$(getconf CLK_TCK)

# measure SERVER PATH BODY CONNECTIONS: one wrk run of $seconds; prints
# requests/s, p50, p99, p99.9 (ms), non-2xx answers, socket errors and the
# server's CPU time per request (µs), tab-separated.
measure() {
  local server=$1 path=$2 body=$3 c=$4 before after result
  for log in "${log_of[@]}"; do : > "$log"; done
  say "$server $path, $c connection(s), ${seconds}s"
  before=$(cpu_ticks "${pid_of[$server]}")
  result=$(GLINT_LOAD_BODY="$body" wrk -t "$((c < 2 ? c : 2))" -c "$c" -d "${seconds}s" \
    --timeout 30s --latency -s "$script" "http://127.0.0.1:${port_of[$server]}$path" |
    grep '^result' | cut -f2-)
  after=$(cpu_ticks "${pid_of[$server]}")
  awk -v r="$result" -v t="$((after - before))" -v hz="$ticks_per_second" -v s="$seconds" 'BEGIN {
    split(r, f, "\t"); n = f[1] * s
    printf "%s\t%.1f\n", r, (n > 0 ? t / hz * 1e6 / n : 0) }'
}

# The median of the arguments.
median() { printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2) }'; }

load_before=$(cut -d' ' -f1-3 /proc/loadavg)

# The small shade in turns: each round runs every server at every number of
# connections, starting from a different server each round.
servers=(bare human json tracing)
declare -A rps p99 p50 cpu bad
for round in $(seq "$rounds"); do
  for c in 16 64; do
    for k in 0 1 2 3; do
      server=${servers[$(((round + k) % 4))]}
      path=/v1/shade
      IFS=$'\t' read -r r q50 q99 _ nok err us < <(measure "$server" "$path" "$small" "$c")
      key="$server/$c"
      rps[$key]+="$r " p50[$key]+="$q50 " p99[$key]+="$q99 " cpu[$key]+="$us "
      bad[$key]=$((${bad[$key]:-0} + nok + err))
    done
  done
done
dropped=()
for name in human json tracing; do
  dropped+=("$(curl -s "http://127.0.0.1:${port_of[$name]}/metrics" |
    awk '$1 == "glint_log_lines_dropped_total" { print $2 }')")
done

# The 100k-vertex chain on one connection, in turns with the parse alone.
declare -A chain
for round in $(seq "$rounds"); do
  for step in parse shade; do
    if [ "$step" = parse ]; then
      IFS=$'\t' read -r r q50 _ _ _ _ _ < <(measure bare /parse "$big" 1)
    else
      IFS=$'\t' read -r r q50 _ _ _ _ _ < <(measure human /v1/shade "$big" 1)
    fi
    chain[$step]+="$r " chain[$step/p50]+="$q50 "
  done
done

# Single runs, for reference.
others=()
other() {
  local name=$1 server=$2 path=$3 body=$4 c=$5 r q50 q99 q999 nok err us
  IFS=$'\t' read -r r q50 q99 q999 nok err us < <(measure "$server" "$path" "$body" "$c")
  others+=("$(printf '| %s | %d | %.1f | %.2f | %.2f | %.2f | %d | %.1f |' "$name" "$c" "$r" "$q50" "$q99" "$q999" "$((nok + err))" "$us")")
}
other "glint: the 3-vertex shade with a term summary" human /v1/shade "$summary" 64
other "bare axum: parse the 100k-vertex body" bare /parse "$big" 16
other "glint: the 100k-vertex shade" human /v1/shade "$big" 16
if [ -n "$render" ]; then
  other "glint: render 640×480 (PNG)" human /v1/render "$render" 1
fi

load_after=$(cut -d' ' -f1-3 /proc/loadavg)

# The tables.
row() {
  local name=$1 server=$2 c=$3
  local key="$server/$c"
  # shellcheck disable=SC2086
  awk -v name="$name" -v c="$c" -v r="$(median ${rps[$key]})" -v q50="$(median ${p50[$key]})" \
    -v q99="$(median ${p99[$key]})" -v us="$(median ${cpu[$key]})" -v bad="${bad[$key]}" \
    -v br="$(median ${rps[bare/$c]})" -v bq="$(median ${p99[bare/$c]})" -v all="${rps[$key]}" \
    'BEGIN { n = split(all, each, " "); for (i = 1; i <= n; i++) list = list (i > 1 ? ", " : "") sprintf("%.0f", each[i])
      printf "| %s | %d | %.0f | %.2f | %.2f | %.1f | %s | %s | %s |", name, c, r, q50, q99, us, list,
      (name ~ /^bare/ ? "—" : sprintf("%.2f×", r / br)), (name ~ /^bare/ ? "—" : sprintf("%.2f×", q99 / bq)) }'
  echo
}
# shellcheck disable=SC2086
ratio_line() {
  local server=$1 label=$2 c
  for c in 16 64; do
    awk -v label="$label" -v c="$c" -v r="$(median ${rps[$server/$c]})" -v br="$(median ${rps[bare/$c]})" \
      -v q="$(median ${p99[$server/$c]})" -v bq="$(median ${p99[bare/$c]})" \
      'BEGIN { printf "- %s, %d connections: %.2f× the bare server'"'"'s requests/s, %.2f× its p99\n", label, c, r / br, q / bq }'
  done
}
# shellcheck disable=SC2086
chain_line=$(awk -v s="$(median ${chain[shade]})" -v p="$(median ${chain[parse]})" \
  -v sl="$(median ${chain[shade/p50]})" -v pl="$(median ${chain[parse/p50]})" -v n="$big_vertices" \
  -v rs="${chain[shade]}" -v rp="${chain[parse]}" \
  'BEGIN { printf "- the 100k-vertex shade on one connection, end to end: %.1f requests/s (%.2f M vertices/s, median latency %.1f ms), against the bare server'"'"'s parse of the same body alone at %.1f requests/s (%.1f ms): the chain takes %.2f× as long as its parse (per round: shade %s; parse %s)", s, s * n / 1e6, sl, p, pl, p / s, rs, rp }')

dirty=$(git status --porcelain 2> /dev/null | grep -q . && echo ", with uncommitted changes" || true)
{
  echo "# Load benchmark"
  echo
  echo "Written by \`benches/load.sh\`; run it again for current figures. The"
  echo "ceiling is \`benches/bare_axum.rs\`: a bare axum server (no middleware,"
  echo "none of glint's layers) that parses the shade body into typed structs and"
  echo "answers as many colour floats, or, for the 100k-vertex body, parses it with"
  echo "serde_json alone. glint runs with its default configuration: access logs"
  echo "on, one line per request at \`info\`, to a file. wrk drives the servers in"
  echo "turns on the same machine; figures are medians of the rounds, and each"
  echo "ratio is glint's median over the bare server's."
  echo
  echo "- command: \`GLINT_LOAD_SECONDS=$seconds GLINT_LOAD_ROUNDS=$rounds benches/load.sh\`"
  echo "- date: $(date -u '+%Y-%m-%d %H:%M UTC')"
  echo "- commit: $(git rev-parse --short HEAD 2> /dev/null || echo unknown)$dirty"
  echo "- machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//'), $(free -g | awk '/^Mem:/ { print $2 }') GiB"
  echo "- load generator: $(wrk -v 2>&1 | head -1 | cut -d' ' -f1-2) on the same machine, \`-t 2 -d ${seconds}s --latency\` per run (\`-t 1\` on one connection), no warm-up"
  echo "- bodies: \`examples/triangle.json\` without its \`terms\` (3 vertices, 2 lights, colours only, $(wc -c < "$small") bytes);"
  echo "  a 100k-vertex grid with the same lights ($(wc -c < "$big") bytes)"
  echo
  echo "## The 3-vertex shade, $rounds rounds in turns"
  echo
  echo "| server | connections | requests/s | p50 ms | p99 ms | server CPU µs/request | requests/s per round | requests/s ÷ bare | p99 ÷ bare |"
  echo "| --- | ---: | ---: | ---: | ---: | ---: | --- | ---: | ---: |"
  for c in 16 64; do
    row "bare axum, the same JSON work" bare "$c"
    row "glint, defaults (human logs)" human "$c"
    row "glint, JSON logs" json "$c"
    row "glint, human logs, the access line by tracing-subscriber" tracing "$c"
  done
  echo
  ratio_line human "glint, human logs"
  ratio_line json "glint, JSON logs"
  ratio_line tracing "glint, human logs, the access line by tracing-subscriber"
  # Paired by round (each round runs both, in turns): the median of the
  # rounds' ratios.
  awk -v own="${rps[human/64]}" -v crate="${rps[tracing/64]}" 'BEGIN {
    n = split(own, o, " "); split(crate, c, " ")
    for (i = 1; i <= n; i++) {
      v = c[i] / o[i]
      for (j = i - 1; j >= 1 && r[j] > v; j--) r[j + 1] = r[j]
      r[j + 1] = v
    }
    m = (n % 2 ? r[(n + 1) / 2] : (r[n / 2] + r[n / 2 + 1]) / 2)
    printf "- the access line by tracing-subscriber, against glint'"'"'s own formatting of it, 64 connections: %.3f× the requests/s, the median of the rounds'"'"' ratios (it costs %.1f%%)\n", m, (1 - m) * 100 }'
  echo "- log lines dropped in these runs (\`glint_log_lines_dropped_total\`): ${dropped[0]} (human), ${dropped[1]} (JSON), ${dropped[2]} (the access line by tracing-subscriber)"
  echo "- answers other than 2xx, and socket errors: $(for k in "${!bad[@]}"; do echo "${bad[$k]}"; done | awk '{ s += $1 } END { print s + 0 }')"
  echo
  echo "## The 100k-vertex shade, $rounds rounds in turns"
  echo
  echo "$chain_line"
  echo
  echo "## Single runs, for reference"
  echo
  echo "| workload | connections | requests/s | p50 ms | p99 ms | p99.9 ms | not 2xx or failed | server CPU µs/request |"
  echo "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  printf '%s\n' "${others[@]}"
  echo
  echo "Notes:"
  echo
  echo "- The load generator shares the machine's $(nproc) cores with the server,"
  echo "  so every figure here is below what a separate client would measure."
  echo "- Server CPU is the server process's user and system time over the run"
  echo "  (its log thread included), divided by the requests it answered."
  echo "- The machine's load average (1, 5 and 15 minutes) was $load_before before"
  echo "  the runs and $load_after after them; the load generator and a server make"
  echo "  about 2 of it, the rest is other work on the machine."
  [ -n "$note" ] && echo "- $note"
  true
} > "$out"
say "wrote $out"
cat "$out"
