# shellcheck shell=bash
# Sourced by the gateway scripts that run inside user-mode-linux, after `build` and `repo` are
# set: the programs, the loopback DDS profile, a scratch directory ($work) whose processes
# ($pids) are ended on exit (with $end_signal, TERM unless the script sets another), check(),
# eventually() and the helpers below (exited, lines, after, section).

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

# A child that has exited stays a zombie until waited for: kill -0 would still find it.
exited() { [ ! -e "/proc/$1" ] || [ "$(awk '{print $3}' "/proc/$1/stat" 2>/dev/null)" = Z ]; }
# lines FILE: how many lines it has (0 before it exists).
lines() { if [ -e "$1" ]; then wc -l <"$1"; else echo 0; fi; }
# after FILE LINE REGEX: REGEX (extended) in FILE after its first LINE lines.
after() { tail -n +"$(($2 + 1))" "$1" | grep -Eq -- "$3"; }
section() { echo "== $* (at ${SECONDS} s)"; }
