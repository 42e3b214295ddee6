# shellcheck shell=bash
# Sourced by the gateway scripts that run inside user-mode-linux, after `build` and `repo` are
# set: the programs, the loopback DDS profile, a scratch directory ($work) whose processes
# ($pids) are ended on exit (with $end_signal, TERM unless the script sets another), check()
# and eventually().

sim="$build/tools/valve-sim/valve-sim"
gateway="$build/gateway/app/teejet-gateway"
valvectl="$build/tools/valvectl/valvectl"
# Fast DDS 2.x reads the first name, later releases the second.
export FASTRTPS_DEFAULT_PROFILES_FILE="$repo/config/fastdds-loopback.xml"
export FASTDDS_DEFAULT_PROFILES_FILE="$FASTRTPS_DEFAULT_PROFILES_FILE"
work=$(mktemp -d)
pids=()
end_signal=${end_signal:-TERM}
cleanup() {
  for pid in "${pids[@]}"; do kill "-$end_signal" "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

failures=0
# check DESCRIPTION COMMAND...: one line per expectation, counted when it fails.
check() {
  local description=$1
  shift
  if "$@"; then
    echo "ok: $description"
  else
    echo "FAIL: $description"
    failures=$((failures + 1))
  fi
}
# shellcheck source=tools/lib/eventually.sh
source "$repo/tools/lib/eventually.sh"
