#!/usr/bin/env bash
# Install every Debian package that building, testing and running the tools of
# teejet-dds-gateway needs. Idempotent: when everything is already installed it
# changes nothing and does not touch the network.
#
# Usage: tools/install-deps.sh          install what is missing
#        tools/install-deps.sh --print  print the package list, one per line
#
# This is the single list of system dependencies: tools/test, tools/demo and
# docker/Dockerfile all run this script.
set -euo pipefail

PACKAGES=(
  # toolchain
  cmake
  gcc
  g++
  make
  ninja-build
  pkg-config
  git
  # DDS: Fast DDS 2.9.1, its CDR library, the IDL generator and CLI tools.
  # fastddsgen is a Java program whose package does not depend on a JRE
  # directly (it only arrives through antlr4), so name one explicitly.
  fastddsgen
  default-jre-headless
  libfastrtps-dev
  libfastcdr-dev
  fastdds-tools
  # a second DDS vendor for the mixed-vendor tests (tests/interop): CycloneDDS
  # 0.10 and its IDL compiler idlc
  cyclonedds-dev
  cyclonedds-tools
  # tests and benchmarks
  libgtest-dev
  libgmock-dev
  googletest
  libbenchmark-dev
  # libraries
  libcli11-dev
  libspdlog-dev
  libfmt-dev
  libyaml-cpp-dev
  nlohmann-json3-dev
  # MCAP recordings (tools/mcap): chunk compression and CRC-32
  libzstd-dev
  liblz4-dev
  zlib1g-dev
  # CAN bus: candump/cansend/vcan, python-can for test scripts
  can-utils
  python3
  python3-can
  # isolated kernel for vcan tests without host privileges
  user-mode-linux
  kmod
  iproute2
  util-linux
  # formatting
  clang-format
  # sanitizer builds and fuzz targets (asan, tsan presets): clang, its sanitizer and libFuzzer
  # runtimes, and llvm-symbolizer (package llvm) for file:line in reports
  clang
  libclang-rt-14-dev
  llvm
)

log() { printf 'install-deps: %s\n' "$*" >&2; }
die() { log "error: $*"; exit 1; }

case "${1:-}" in
  --print)
    printf '%s\n' "${PACKAGES[@]}"
    exit 0
    ;;
  -h | --help)
    sed -n '2,10s/^# \{0,1\}//p' "$0"
    exit 0
    ;;
  "") ;;
  *) die "unknown argument '$1' (try --help)" ;;
esac

for tool in dpkg-query apt-get; do
  command -v "$tool" >/dev/null 2>&1 ||
    die "$tool not found: this script needs a Debian-based system"
done

is_installed() {
  [[ "$(dpkg-query -W -f='${Status}' "$1" 2>/dev/null || true)" == "install ok installed" ]]
}

missing_packages() {
  local pkg
  for pkg in "${PACKAGES[@]}"; do
    is_installed "$pkg" || printf '%s\n' "$pkg"
  done
}

mapfile -t missing < <(missing_packages)
if ((${#missing[@]} == 0)); then
  log "all ${#PACKAGES[@]} packages already installed"
  exit 0
fi
log "missing ${#missing[@]} package(s): ${missing[*]}"

# Run a command as root: directly when root, through sudo otherwise.
as_root() {
  if ((EUID == 0)); then
    "$@"
  elif command -v sudo >/dev/null 2>&1; then
    sudo "$@"
  else
    die "not running as root and sudo is not installed; rerun as root: $0"
  fi
}

# env, not an exported variable: sudo resets the environment.
as_root env DEBIAN_FRONTEND=noninteractive apt-get update
as_root env DEBIAN_FRONTEND=noninteractive \
  apt-get install -y --no-install-recommends "${missing[@]}"

mapfile -t still_missing < <(missing_packages)
((${#still_missing[@]} == 0)) || die "still not installed: ${still_missing[*]}"
log "installed ${#missing[@]} package(s)"
