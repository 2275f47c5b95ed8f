#!/usr/bin/env bash
# The playground's latency in the browser: the time from a control's change
# to its preview on screen, for the spheres example, against the release
# server (benches/playground_latency.mjs says how it is measured).
#
#   benches/playground_latency.sh [--samples N]
#
# Needs Node with npm and Debian's chromium (`cargo test` installs it, as
# root, for the playground's browser test). Playwright's core is installed
# under target/tools/node-playground from tests/playground/package-lock.json
# when it is not there yet. Traffic goes to 127.0.0.1 only; the server it
# starts is stopped when it ends.
set -euo pipefail

cd "$(dirname "$0")/.."
dir="$PWD/target/tools/node-playground"
[ -x /usr/bin/chromium ] || [ -n "${GLINT_CHROMIUM:-}" ] || {
  echo "playground_latency.sh: needs chromium (apt-get install chromium)" >&2
  exit 1
}
if ! cmp -s tests/playground/package-lock.json "$dir/installed-from"; then
  rm -rf "$dir"
  mkdir -p "$dir"
  cp tests/playground/package.json tests/playground/package-lock.json "$dir/"
  (cd "$dir" && PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --ignore-scripts --no-audit --no-fund)
  cp tests/playground/package-lock.json "$dir/installed-from"
fi
cargo build --release --bin glint
node benches/playground_latency.mjs --glint target/release/glint --playwright "$dir" "$@"
