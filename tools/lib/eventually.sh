# shellcheck shell=bash
# Waiting on a condition with a deadline, for the project's shell scripts (tests, benchmarks):
# never a fixed sleep standing in for "it has happened by now".

# scaled_seconds SECONDS: SECONDS times TEEJET_DEADLINE_SCALE where that is set (tools/test sets
# it for every test, the user-mode-linux tests through tests/uml/CMakeLists.txt;
# tests/support/eventually.hpp reads the same for C++): a deadline only bounds how long a
# failure takes to show.
scaled_seconds() { echo $(($1 * ${TEEJET_DEADLINE_SCALE:-1})); }

# eventually SECONDS COMMAND...: runs COMMAND until it succeeds (true) or SECONDS (scaled) pass
# (false).
eventually() {
  local deadline=$((SECONDS + $(scaled_seconds "$1")))
  shift
  until "$@"; do
    [ "$SECONDS" -ge "$deadline" ] && return 1
    sleep 0.1
  done
}
