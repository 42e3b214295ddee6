#!/usr/bin/env bash
# Install every Debian package that building, testing and running the tools of
# teejet-dds-gateway needs, and the npm packages of the independent MCAP reader
# (tests/mcap-js) and of the dashboard's QR decoder (tools/teejet-web/qr), each pinned in its
# package-lock.json. Idempotent: when everything is
# already installed it changes nothing and does not touch the network.
#
# Usage: tools/install-deps.sh               install what is missing
#        tools/install-deps.sh --print       print the package list, one per line
#        tools/install-deps.sh --build-only  only what compiling the programs needs
#                                            (no tests, tools, npm); --print combines
#
# This is the single list of system dependencies: tools/test, tools/demo and
# docker/Dockerfile (--build-only) all run this script.
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
  # the HTTP and WebSocket server of teejet-web (tools/teejet-web): Boost.Beast and Asio,
  # header-only; OpenSSL's headers for Beast's TLS streams
  libboost-dev
  libssl-dev
  # MCAP recordings (gateway/mcap): chunk compression and CRC-32
  libzstd-dev
  liblz4-dev
  zlib1g-dev
  # CAN bus: candump/cansend/vcan, python-can for test scripts
  can-utils
  python3
  python3-can
  # the dashboard's browser test (tests/web/browser_test.py): headless Chromium driven by Selenium
  chromium
  chromium-driver
  python3-selenium
  # its https test trusts the test's own CA through an NSS database (certutil)
  libnss3-tools
  # tools/demo carries the dashboard out of its network namespace through a Unix socket
  socat
  # docs/recording.md's plot of a recording (tools/plot-recording.py)
  python3-matplotlib
  # a recorder whose wall clock steps (tests/recording/recording_e2e.py clock-step): libfaketime
  faketime
  # isolated kernel for vcan tests without host privileges
  user-mode-linux
  kmod
  iproute2
  util-linux
  # formatting
  clang-format
  # tools/test compiles through it: a second run of the suite recompiles only what changed
  ccache
  # DDS-Security material (tools/pki): the openssl command line
  openssl
  # Debian packages (tools/package/build): Debian's packaging tools, the man pages made from each
  # program's --help, and lintian, which CI runs on the packages
  dpkg-dev
  debhelper
  fakeroot
  help2man
  lintian
  # (Node and npm for tests/mcap-js and tools/teejet-web/qr: see NODE_PACKAGES below)
  # the QR code of a valve's serial, for the dashboard's camera test (tests/web/qr_video.py)
  qrencode
  # sanitizer builds and fuzz targets (asan, tsan presets): clang, its sanitizer and libFuzzer
  # runtimes, and llvm-symbolizer (package llvm) for file:line in reports
  clang
  libclang-rt-14-dev
  llvm
)

# What configuring the release preset with BUILD_TESTING=OFF and compiling the programs needs
# (docker/Dockerfile's builder stage, tools/package/build): a compiler and the Build-Depends of
# tools/package/debian/control, the one list of them, less what only makes the packages.
SOURCE_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
CONTROL="$SOURCE_ROOT/tools/package/debian/control"
build_depends() {
  [[ -f "$CONTROL" ]] || die "$CONTROL is missing: it lists what building needs"
  sed -n '/^Build-Depends:/,/^[A-Z]/{s/^Build-Depends://;/^[A-Z]/d;p}' "$CONTROL" |
    tr ',' '\n' | sed -e 's/([^)]*)//g' -e 's/:native//' -e 's/[[:space:]]//g' |
    grep -v -e '^$' -e '^debhelper-compat$' -e '^help2man$'
}

# Node (18 or newer) and npm run the independent MCAP reader of tests/mcap-js and fetch the QR
# decoder teejet-web serves (tools/teejet-web/qr; without it the page's setup view offers no
# camera, and the build says so). Debian's
# packages only when the commands are missing: a Node from elsewhere (nodesource bundles npm)
# conflicts with Debian's npm package and serves as well.
NODE_PACKAGES=()
command -v node >/dev/null 2>&1 || NODE_PACKAGES+=(nodejs)
command -v npm >/dev/null 2>&1 || NODE_PACKAGES+=(npm)

log() { printf 'install-deps: %s\n' "$*" >&2; }
die() { log "error: $*"; exit 1; }

print=0 build_only=0
for arg in "$@"; do
  case "$arg" in
    --print) print=1 ;;
    --build-only) build_only=1 ;;
    -h | --help)
      sed -n '2,13s/^# \{0,1\}//p' "$0"
      exit 0
      ;;
    *) die "unknown argument '$arg' (try --help)" ;;
  esac
done

if ((build_only)); then
  mapfile -t PACKAGES < <(printf '%s\n' gcc g++ && build_depends)
  ((${#PACKAGES[@]} > 10)) || die "could not read the Build-Depends of $CONTROL"
else
  PACKAGES+=("${NODE_PACKAGES[@]}")
fi

if ((print)); then
  printf '%s\n' "${PACKAGES[@]}"
  exit 0
fi

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

install_debian_packages() {
  local missing still_missing
  mapfile -t missing < <(missing_packages)
  if ((${#missing[@]} == 0)); then
    log "all ${#PACKAGES[@]} packages already installed"
    return
  fi
  log "missing ${#missing[@]} package(s): ${missing[*]}"
  # env, not an exported variable: sudo resets the environment.
  as_root env DEBIAN_FRONTEND=noninteractive apt-get update
  as_root env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y --no-install-recommends "${missing[@]}"

  mapfile -t still_missing < <(missing_packages)
  ((${#still_missing[@]} == 0)) || die "still not installed: ${still_missing[*]}"
  log "installed ${#missing[@]} package(s)"
}

# As the user who runs this script (not root through sudo), so that node_modules is theirs.
install_npm_packages() {
  local dir="$SOURCE_ROOT/$1" what="$2" want have=""
  local lockfile="$dir/package-lock.json"
  # npm ci runs when the lockfile differs from the one node_modules was installed from, whose
  # sha256 the stamp holds; npm ci empties node_modules first, so a failed install leaves none.
  local stamp="$dir/node_modules/.teejet-lockfile-sha256"
  if [[ ! -f "$lockfile" ]]; then
    # e.g. docker/Dockerfile, which runs this script before copying the sources
    log "no $lockfile: npm packages of $1 not installed"
    return
  fi
  command -v node >/dev/null 2>&1 || die "node not found after installing nodejs"
  command -v npm >/dev/null 2>&1 || die "npm not found after installing npm"
  node -e 'process.exit(Number(process.versions.node.split(".")[0]) >= 18 ? 0 : 1)' ||
    die "node $(node --version) is too old: $1 needs Node 18 or newer"
  want="$(sha256sum "$lockfile" | cut -d' ' -f1)"
  [[ -f "$stamp" ]] && have="$(<"$stamp")"
  if [[ "$have" == "$want" ]]; then
    log "npm packages of $1 ($what) already installed"
    return
  fi
  log "installing the npm packages of $1 ($what; npm ci)"
  (cd "$dir" && npm ci --no-audit --no-fund) || die "npm ci in $dir failed"
  printf '%s\n' "$want" >"$stamp"
  log "installed the npm packages of $1"
}

install_debian_packages
if ! ((build_only)); then
  install_npm_packages tests/mcap-js "the independent MCAP reader"
  install_npm_packages tests/foxglove-layout "the Foxglove layout check"
  install_npm_packages tests/foxglove "the Foxglove WebSocket test client"
  install_npm_packages tools/teejet-web/qr "the dashboard's QR decoder"
fi
