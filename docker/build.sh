#!/usr/bin/env bash
# Builds glint's container image, from the repository root:
#
#   docker/build.sh [TAG]
#
# First the static binary (cargo, for x86_64-unknown-linux-gnu with glibc
# linked in, so that it runs on an empty root), then docker/Dockerfile on a
# context that holds that binary alone. The image is tagged TAG, or by
# default glint:latest and glint:VERSION (the crate's version, the tag the
# Kubernetes manifests name).
#
# The engine: docker where its daemon answers, else podman;
# GLINT_ENGINE=docker|podman chooses (docker/engine.sh). podman builds in
# Docker's image format, which keeps HEALTHCHECK (the OCI format has no
# such field, and podman would drop it). Nothing is pulled: the image starts
# from scratch.
set -euo pipefail

repo="$(cd "$(dirname "$0")/.." && pwd)"
source "$repo/docker/engine.sh"

version="$(sed -n 's/^version = "\(.*\)"$/\1/p' "$repo/Cargo.toml" | head -n 1)"
if (($#)); then
    tags=("$1")
else
    tags=("glint:latest" "glint:$version")
fi

triple=x86_64-unknown-linux-gnu
# --target keeps the static flag off the build scripts and proc macros,
# which the host's dynamic toolchain loads; and keeps this build apart from
# the ordinary one in target/release. The symbol table is left out (some
# 3.5 MB of the image, which must stay under 30 MB): a panic's backtrace
# in a container names addresses rather than functions.
(cd "$repo" && RUSTFLAGS="${RUSTFLAGS:+$RUSTFLAGS }-C target-feature=+crt-static -C strip=symbols" \
    cargo build --release --locked --target "$triple" --bin glint)
binary="${CARGO_TARGET_DIR:-$repo/target}/$triple/release/glint"

context="$(mktemp -d "${TMPDIR:-/tmp}/glint-image.XXXXXX")"
trap 'rm -rf "$context"' EXIT
cp "$binary" "$context/glint"

format=()
[[ "$engine" == podman ]] && format=(--format docker)
tag_flags=()
for tag in "${tags[@]}"; do tag_flags+=(--tag "$tag"); done
"$engine" build "${format[@]}" "${tag_flags[@]}" --file "$repo/docker/Dockerfile" "$context"
echo "built ${tags[*]} with $engine"
