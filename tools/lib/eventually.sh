# shellcheck shell=bash
# Waiting on a condition with a deadline, for the project's shell scripts (tests, benchmarks):
# never a fixed sleep standing in for "it has happened by now".

# eventually SECONDS COMMAND...: runs COMMAND until it succeeds (true) or SECONDS pass (false),
# SECONDS times TEEJET_DEADLINE_SCALE where that is set (the user-mode-linux tests set it:
# tests/uml/CMakeLists.txt).
eventually() {
  local deadline=$((SECONDS + $1 * ${TEEJET_DEADLINE_SCALE:-1}))
  shift
  until "$@"; do
    [ "$SECONDS" -ge "$deadline" ] && return 1
    sleep 0.1
  done
}
