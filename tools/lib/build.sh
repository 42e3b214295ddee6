# shellcheck shell=bash
# Shared configure/build steps, sourced by tools/test, tools/demo and
# docker/Dockerfile. Sourcing it cds to the repository root and sets:
#   REPO_ROOT  absolute path of the repository
#   BUILD_DIR  build directory (env BUILD_DIR, default "build", relative to REPO_ROOT)
#   PRESET     CMakePresets.json configure preset (env PRESET, default "ci": Release with
#              warnings as errors; "dev" for RelWithDebInfo, "release" for a consumer's build)

REPO_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD_DIR="${BUILD_DIR:-build}"
PRESET="${PRESET:-ci}"
cd "$REPO_ROOT" || return 1

tj_install_deps() {
  "$REPO_ROOT/tools/install-deps.sh"
}

tj_configure() {
  cmake --preset "$PRESET" -B "$BUILD_DIR"
}

tj_build() {
  cmake --build "$BUILD_DIR" -j"$(nproc)"
}

# Microseconds since the epoch (EPOCHREALTIME's decimal separator follows the locale).
tj_now_us() {
  printf '%s\n' "${EPOCHREALTIME//[!0-9]/}"
}

# Seconds, with one decimal, between two tj_now_us values.
tj_elapsed() {
  local us=$(($2 - $1))
  printf '%d.%ds' $((us / 1000000)) $((us % 1000000 / 100000))
}
