# The container engine of the build scripts, sourced by them: docker where
# its daemon answers, else podman; GLINT_ENGINE=docker|podman chooses. Sets
# `engine`, or says why there is none and exits.

engine="${GLINT_ENGINE:-}"
if [[ -z "$engine" ]]; then
    # A docker client alone (no daemon to answer it) cannot build.
    if command -v docker >/dev/null && docker info >/dev/null 2>&1; then
        engine=docker
    elif command -v podman >/dev/null; then
        engine=podman
    else
        echo "$(basename "$0"): neither docker (with its daemon) nor podman is installed" \
            "(Debian: apt-get install podman runc)" >&2
        exit 1
    fi
fi
case "$engine" in
    docker | podman) command -v "$engine" >/dev/null || {
        echo "$(basename "$0"): GLINT_ENGINE=$engine, which is not installed" >&2
        exit 1
    } ;;
    *) echo "$(basename "$0"): GLINT_ENGINE must be docker or podman, not $engine" >&2; exit 2 ;;
esac
