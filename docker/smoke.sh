#!/usr/bin/env bash
# Build docker/Dockerfile with Podman and check the image works: a developer's check, run as
# root on a Debian host (CI does not run it; it downloads packages and takes ~15 min on 2 cores).
#
# Usage: docker/smoke.sh   (no arguments; prints a PASS/FAIL summary, exits 1 if a check failed)
#
# Steps: installs podman, buildah, debootstrap and runc when missing; makes a Debian bookworm
# base image with `debootstrap --variant=minbase` from this host's mirror (cached in
# $TEEJET_CONTAINER_CACHE, default /var/cache/teejet-containers, and as a local image, shared
# with tools/package: tools/lib/container.sh; a second run
# skips it); builds the Dockerfile on it; reports the image size and the build time; runs the
# image with --network none (its own loopback only: DDS traffic never leaves the container).
# Only `podman build` gets the host network, for apt's package downloads; no DDS program runs
# during the build.

# The single-quoted scripts below are expanded by bash inside the container, not here.
# shellcheck disable=SC2016
set -euo pipefail

REPO_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=tools/lib/container.sh
source "$REPO_ROOT/tools/lib/container.sh"
IMAGE="localhost/teejet-dds-gateway:smoke"
# Size the runtime image must stay under (docker/README.md).
MAX_IMAGE_MB=300

log() { printf 'smoke: %s\n' "$*" >&2; }
die() { log "error: $*"; exit 1; }

case "${1:-}" in
  "") ;;
  -h | --help) sed -n '2,13s/^# \{0,1\}//p' "$0"; exit 0 ;;
  *) die "unknown argument '$1' (try --help)" ;;
esac
((EUID == 0)) || die "run as root: podman, debootstrap and apt-get need it"

# shellcheck source=tools/lib/results.sh
source "$REPO_ROOT/tools/lib/results.sh"
trap 'tj_summary "docker/smoke.sh summary"' EXIT

# --- tools ---------------------------------------------------------------------------------------
tj_podman_setup
RUN=("${PODMAN[@]}" run --rm --network none "${TJ_ULIMITS[@]}")

log "disk space:"
df -h /var >&2
avail_kb=$(df --output=avail -k /var | tail -1)
((avail_kb > 8 * 1024 * 1024)) || die "less than 8 GB free on /var: the build needs ~4 GB"

# --- base image ---------------------------------------------------------------------------------
BASE_IMAGE=$(tj_debian_base_image)
log "base image $BASE_IMAGE"

# --- build --------------------------------------------------------------------------------------
log "building $IMAGE (the first build compiles everything: ~10-20 min on 2 cores)"
start=$SECONDS
if "${PODMAN[@]}" build --network host "${TJ_ULIMITS[@]}" --build-arg "BASE_IMAGE=$BASE_IMAGE" \
  -f "$REPO_ROOT/docker/Dockerfile" -t "$IMAGE" "$REPO_ROOT"; then
  tj_pass "podman build (OCI format) in $((SECONDS - start)) s"
else
  tj_fail "podman build (OCI format) after $((SECONDS - start)) s"
  exit 1
fi

size=$("${PODMAN[@]}" image inspect --format '{{.Size}}' "$IMAGE")
size_mb=$((size / 1000 / 1000))
if ((size_mb < MAX_IMAGE_MB)); then
  tj_pass "image size ${size_mb} MB (< ${MAX_IMAGE_MB} MB)"
else
  tj_fail "image size ${size_mb} MB (limit ${MAX_IMAGE_MB} MB)"
fi

# --- checks, every one with --network none ------------------------------------------------------
# check NAME EXPECTED_OUTPUT_REGEX COMMAND...: passes when COMMAND exits 0 and prints a match.
check() {
  local name=$1 want=$2 out status=0
  shift 2
  out=$("$@" 2>&1) || status=$?
  printf '%s\n' "$out" | sed 's/^/    | /' >&2
  if ((status == 0)) && grep -Eq -- "$want" <<<"$out"; then
    tj_pass "$name"
  else
    tj_fail "$name (exit $status, wanted output matching '$want')"
  fi
}

check "teejet-gateway --version (entrypoint)" '^teejet-gateway [0-9]+\.[0-9]+\.[0-9]+' \
  "${RUN[@]}" "$IMAGE" --version
check "teejet-gateway --help" 'Usage:.*teejet-gateway' "${RUN[@]}" "$IMAGE" --help
check "runs as the non-root user teejet (uid 10001)" '^10001 teejet$' \
  "${RUN[@]}" --entrypoint bash "$IMAGE" -c 'echo "$(id -u) $(id -un)"'
check "every program and library resolves (ldd)" '^all resolved$' \
  "${RUN[@]}" --entrypoint bash "$IMAGE" -c '
    for f in /opt/teejet/bin/*; do
      ldd "$f" | grep "not found" && { echo "$f: missing libraries"; exit 1; }
    done
    echo "all resolved"'
for tool in valvectl valve-sim valve-decode teejet-record teejet-replay teejet-web; do
  check "$tool --version" "^$tool [0-9]" "${RUN[@]}" --entrypoint "$tool" "$IMAGE" --version
done
# teejet-web (a DDS participant: --network none keeps it to the container's loopback) finds its
# page where the image installed it.
check "teejet-web serves its page from /opt/teejet/share/teejet-web/www" \
  'page from /opt/teejet/share/teejet-web/www' \
  "${RUN[@]}" --entrypoint bash "$IMAGE" -c 'timeout -s INT 3 teejet-web 2>&1; true'

# The gateway on 4 simulated valves, valvectl finding them and moving one to 90 degrees, all in
# one container: the loopback profile keeps DDS on shared memory and 127.0.0.1.
check "gateway --can sim:4, valvectl list --wait-for 4, move TJV000002 --to 90 --wait" \
  'gateway exited 0' \
  "${RUN[@]}" --entrypoint bash "$IMAGE" -euo pipefail -c '
    profile=/etc/teejet/fastdds-loopback.xml
    teejet-gateway --can sim:4 --profile "$profile" --log-level warn &
    gw=$!
    valvectl --profile "$profile" --timeout 20 list --wait-for 4
    valvectl --profile "$profile" move TJV000002 --to 90 --wait
    valvectl --profile "$profile" list | grep -E "SERIAL|TJV000002"
    kill -TERM "$gw"
    status=0
    wait "$gw" || status=$?
    echo "gateway exited $status"'

# The discovery server of docker/compose.yaml, and a gateway and valvectl as its clients through
# ROS_DISCOVERY_SERVER (no profile: Fast DDS then discovers through the server only). Before
# the server starts, valvectl must not find the gateway: the clients really depend on it.
check "fast-discovery-server on 11811, gateway and valvectl as clients (ROS_DISCOVERY_SERVER)" \
  'gateway exited 0' \
  "${RUN[@]}" --entrypoint bash "$IMAGE" -euo pipefail -c '
    export ROS_DISCOVERY_SERVER=127.0.0.1:11811
    teejet-gateway --can sim:2 --log-level warn &
    gw=$!
    if valvectl --timeout 3 list --wait-for 2; then
      echo "valvectl found the gateway without the discovery server"
      exit 1
    fi
    echo "without the server: not found, as it must be"
    fast-discovery-server -i 0 -l 127.0.0.1 -p 11811 &
    server=$!
    valvectl --timeout 20 list --wait-for 2
    kill -TERM "$gw"
    status=0
    wait "$gw" || status=$?
    kill -TERM "$server"
    wait "$server" || true
    echo "gateway exited $status"'

((TJ_FAILED == 0))
