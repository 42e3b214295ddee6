# shellcheck shell=bash
# Waiting on a condition with a deadline, for the project's shell scripts (tests, benchmarks):
# never a fixed sleep standing in for "it has happened by now".

# eventually SECONDS COMMAND...: runs COMMAND until it succeeds (true) or SECONDS pass (false).
eventually() {
  local deadline=$((SECONDS + $1))
  shift
  until "$@"; do
    [ "$SECONDS" -ge "$deadline" ] && return 1
    sleep 0.1
  done
}
