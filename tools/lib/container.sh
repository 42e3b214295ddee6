# shellcheck shell=bash
# Podman on this kind of host, and the Debian 12 images the container checks start from; sourced
# by docker/smoke.sh and tools/package. Run as root (podman, debootstrap and apt-get need it).
#   tj_podman_setup          installs podman, buildah, debootstrap and runc when missing; sets
#                            PODMAN (the command, with --runtime runc and, when the kernel has no
#                            overlay for it, --storage-driver vfs) and TJ_ULIMITS
#   tj_debian_base_image     makes localhost/teejet-bookworm-minbase (debootstrap --variant=minbase
#                            of this host's mirror) unless it exists; prints its name
#   tj_cross_image ARCH      makes localhost/teejet-cross-ARCH: the base, ARCH's cross compilers and
#                            this project's build dependencies for ARCH (apt-get build-dep from
#                            tools/package/debian/control); prints its name
# TEEJET_CONTAINER_CACHE (default /var/cache/teejet-containers) keeps the debootstrap tarball and
# TJ_CROSS_CCACHE, the compiler cache of every cross build (the packages' and check-arm64's
# suites), whichever checkout they come from.

TJ_CONTAINER_CACHE="${TEEJET_CONTAINER_CACHE:-/var/cache/teejet-containers}"
TJ_CROSS_CCACHE="$TJ_CONTAINER_CACHE/ccache"
TJ_BASE_IMAGE="localhost/teejet-bookworm-minbase:latest"
TJ_SOURCE_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"

tj_container_log() { printf 'container: %s\n' "$*" >&2; }
tj_container_die() { tj_container_log "error: $*"; exit 1; }

tj_podman_setup() {
  ((EUID == 0)) || tj_container_die "run as root: podman, debootstrap and apt-get need it"
  local missing=() pkg
  for pkg in podman buildah debootstrap runc; do
    [[ "$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null || true)" == "install ok installed" ]] ||
      missing+=("$pkg")
  done
  if ((${#missing[@]} > 0)); then
    tj_container_log "installing ${missing[*]}"
    DEBIAN_FRONTEND=noninteractive apt-get update
    DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}"
  fi
  # This sandbox needs runc and explicit limits: Podman's defaults (nofile 1048576) exceed the
  # hard limits runc may set here, and so does an nproc of 65536 even under a higher hard limit.
  # This shell's own open-file limit, and at most 32768 processes.
  PODMAN=(podman --runtime runc)
  local nofile nproc
  nofile=$(ulimit -Hn) nproc=$(ulimit -Hu)
  [[ "$nproc" == unlimited ]] || ((nproc > 32768)) && nproc=32768
  TJ_ULIMITS=(--ulimit "nofile=$nofile:$nofile" --ulimit "nproc=$nproc:$nproc")
  # Overlay when the kernel allows it, vfs (slow, large, but works everywhere) otherwise.
  if ! "${PODMAN[@]}" info >/dev/null 2>&1; then
    tj_container_log "podman does not start with its default storage: using --storage-driver vfs"
    PODMAN+=(--storage-driver vfs)
  fi
}

# The first URIs of this host's debian.sources (e.g. a snapshot or a local mirror).
tj_debian_mirror() {
  local sources=/etc/apt/sources.list.d/debian.sources uri=""
  [[ -f "$sources" ]] && uri=$(awk '/^URIs:/ {print $2; exit}' "$sources")
  printf '%s\n' "${uri:-http://deb.debian.org/debian}"
}

tj_debian_base_image() {
  local tarball="$TJ_CONTAINER_CACHE/bookworm-minbase.tar"
  if "${PODMAN[@]}" image exists "$TJ_BASE_IMAGE"; then
    printf '%s\n' "$TJ_BASE_IMAGE"
    return
  fi
  if [[ ! -s "$tarball" ]]; then
    mkdir -p "$TJ_CONTAINER_CACHE"
    local rootfs="$TJ_CONTAINER_CACHE/rootfs.tmp"
    rm -rf "$rootfs"
    tj_container_log "debootstrap --variant=minbase bookworm from $(tj_debian_mirror)"
    debootstrap --variant=minbase bookworm "$rootfs" "$(tj_debian_mirror)" \
      >"$TJ_CONTAINER_CACHE/debootstrap.log" 2>&1 ||
      tj_container_die "debootstrap failed: see $TJ_CONTAINER_CACHE/debootstrap.log"
    # Slim like debian:bookworm-slim: no downloaded .debs, package lists (whoever uses the image
    # runs apt-get update itself), manuals or translations, neither now nor in later installs.
    rm -rf "$rootfs"/var/lib/apt/lists/* "$rootfs"/var/cache/apt/*.bin \
      "$rootfs"/var/cache/apt/archives/*.deb
    cat >"$rootfs/etc/dpkg/dpkg.cfg.d/docker-slim" <<'EOF'
path-exclude /usr/share/doc/*
path-include /usr/share/doc/*/copyright
path-exclude /usr/share/man/*
path-exclude /usr/share/info/*
path-exclude /usr/share/locale/*
EOF
    # Files only: packages' scripts expect the directories (openjdk's postinst links into man1).
    find "$rootfs"/usr/share/doc -mindepth 2 ! -name copyright ! -type d -delete
    find "$rootfs"/usr/share/man "$rootfs"/usr/share/info "$rootfs"/usr/share/locale \
      ! -type d -delete
    tar -C "$rootfs" --numeric-owner -cf "$tarball.tmp" .
    mv "$tarball.tmp" "$tarball"
    rm -rf "$rootfs"
  fi
  tj_container_log "importing $tarball as $TJ_BASE_IMAGE"
  "${PODMAN[@]}" import --change 'CMD ["bash"]' "$tarball" "$TJ_BASE_IMAGE" >/dev/null
  printf '%s\n' "$TJ_BASE_IMAGE"
}

# The image is remade when the control file's build dependencies change (a label holds their
# hash), so a new dependency reaches the cross build without anyone deleting the image by hand.
tj_cross_image() {
  local arch=$1 image="localhost/teejet-cross-$1:latest" control deps_hash base
  control="$TJ_SOURCE_ROOT/tools/package/debian/control"
  deps_hash=$(sed -n '/^Build-Depends:/,/^[A-Z]/p' "$control" | sha256sum | cut -c1-16)
  if "${PODMAN[@]}" image exists "$image" &&
    [[ "$("${PODMAN[@]}" image inspect --format '{{index .Labels "teejet.build-deps"}}' "$image")" == "$deps_hash" ]]; then
    printf '%s\n' "$image"
    return
  fi
  base=$(tj_debian_base_image)
  tj_container_log "making $image (cross compilers and the build dependencies for $arch)"
  local name="teejet-cross-$arch-make"
  "${PODMAN[@]}" rm -f "$name" >/dev/null 2>&1 || true
  # apt needs the host network here (package downloads only; no DDS program runs).
  "${PODMAN[@]}" run --name "$name" --network host "${TJ_ULIMITS[@]}" \
    -v "$TJ_SOURCE_ROOT/tools/package/debian/control:/tmp/teejet/debian/control:ro" \
    "$base" bash -euo pipefail -c "
      export DEBIAN_FRONTEND=noninteractive
      mkdir -p /usr/share/man/man1
      dpkg --add-architecture $arch
      apt-get update
      apt-get install -y --no-install-recommends build-essential crossbuild-essential-$arch \
        dpkg-dev debhelper fakeroot ccache qemu-user-static
      apt-get build-dep -y --host-architecture $arch /tmp/teejet
      apt-get clean
      rm -rf /var/lib/apt/lists/*" >&2 ||
    tj_container_die "could not make $image (see the apt output above)"
  "${PODMAN[@]}" commit --change "LABEL teejet.build-deps=$deps_hash" "$name" "$image" >/dev/null
  "${PODMAN[@]}" rm "$name" >/dev/null
  printf '%s\n' "$image"
}
