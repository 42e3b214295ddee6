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

# tj_configure [PRESET [DIR]]: defaults $PRESET and $BUILD_DIR. With TEEJET_CCACHE=1 (tools/test
# sets it when ccache is installed) every compile goes through ccache; CCACHE_BASEDIR makes the
# cache's keys relative to the checkout, so a fresh clone elsewhere reuses what another compiled.
tj_configure() {
  local launcher=()
  if [[ "${TEEJET_CCACHE:-0}" == 1 ]]; then
    export CCACHE_BASEDIR="$REPO_ROOT"
    launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  fi
  cmake --preset "${1:-$PRESET}" -B "${2:-$BUILD_DIR}" "${launcher[@]}"
}

# tj_build [DIR [TARGET...]]: defaults $BUILD_DIR and every target.
tj_build() {
  local dir="${1:-$BUILD_DIR}"
  shift $(($# > 0 ? 1 : 0))
  if (($# > 0)); then
    cmake --build "$dir" -j"$(nproc)" --target "$@"
  else
    cmake --build "$dir" -j"$(nproc)"
  fi
}

# Microseconds since the epoch (EPOCHREALTIME's decimal separator follows the locale).
tj_now_us() {
  printf '%s\n' "${EPOCHREALTIME//[!0-9]/}"
}

# CPU time (user + system, milliseconds) of every child process this shell has waited for, and of
# their children that they waited for: the difference across a step is what the step cost the
# machine, whatever else shared it. (/proc/PID/stat after the command name: the children's user
# and system clock ticks are the 14th and 15th fields.) tj_cpu_ms [PID]: of that shell instead;
# a subshell passes its own, $BASHPID ($$ stays the parent's there).
tj_cpu_ms() {
  local stat
  stat=$(<"/proc/${1:-$$}/stat")
  stat=${stat##*) }
  awk -v fields="$stat" -v hz="$(getconf CLK_TCK)" \
    'BEGIN { split(fields, f, " "); printf "%d\n", (f[14] + f[15]) * 1000 / hz }'
}

# Seconds, with one decimal, between two tj_now_us values.
tj_elapsed() {
  local us=$(($2 - $1))
  printf '%d.%ds' $((us / 1000000)) $((us % 1000000 / 100000))
}
