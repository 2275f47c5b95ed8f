#!/usr/bin/env bash
# Builds the HAProxy image of deploy/compose.yaml here, from Debian's
# packages alone, for a host that can pull no image:
#
#   deploy/haproxy/build.sh [TAG]          # default glint-haproxy:latest
#
# debootstrap makes a minimal Debian root with Debian's haproxy in it, and
# the engine (docker/engine.sh: docker where its daemon answers, else
# podman) imports that root as an image that runs
# `haproxy -f /usr/local/etc/haproxy/haproxy.cfg` as the user haproxy, as the
# official image does; compose mounts the configuration there. A host that
# can pull needs none of this: GLINT_HAPROXY_IMAGE=haproxy:2.6 points
# compose at the official image (docs/deploy.md).
#
# Needs root and debootstrap (Debian: apt-get install debootstrap).
# GLINT_DEBIAN_MIRROR names another mirror.
set -euo pipefail

repo="$(cd "$(dirname "$0")/../.." && pwd)"
source "$repo/docker/engine.sh"
tag="${1:-glint-haproxy:latest}"
mirror="${GLINT_DEBIAN_MIRROR:-http://deb.debian.org/debian}"

command -v debootstrap >/dev/null || {
    echo "build.sh: debootstrap is not installed (Debian: apt-get install debootstrap)" >&2
    exit 1
}
root="$(mktemp -d "${TMPDIR:-/var/tmp}/glint-haproxy-root.XXXXXX")"
trap 'rm -rf "$root"' EXIT
debootstrap --variant=minbase --include=haproxy bookworm "$root" "$mirror"
# What a running balancer never reads.
rm -rf "$root"/var/lib/apt/lists/* "$root"/var/cache/apt/* \
    "$root"/usr/share/doc/* "$root"/usr/share/man/* "$root"/usr/share/locale/*
mkdir -p "$root/usr/local/etc/haproxy"
# STOPSIGNAL is not among docker import's changes: compose sets SIGUSR1
# (HAProxy's soft stop) itself.
tar -C "$root" -c . | "$engine" import \
    --change 'USER haproxy' \
    --change 'WORKDIR /var/lib/haproxy' \
    --change 'EXPOSE 8080' \
    --change 'CMD ["haproxy", "-f", "/usr/local/etc/haproxy/haproxy.cfg"]' \
    - "$tag"
echo "built $tag with $engine"
