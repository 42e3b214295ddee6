# shellcheck shell=bash
# The PASS/FAIL lines of a check script and its summary at the end; sourced by docker/smoke.sh
# and tools/package/check, check-arm64. The script defines log (its own prefix on stderr).
#   tj_pass WHAT, tj_fail WHAT   a result line now, and in the summary; TJ_FAILED=1 after a fail
#   tj_check WHAT COMMAND...     COMMAND's output indented as it runs, then PASS when it exits 0,
#                                FAIL otherwise; returns COMMAND's status
#   tj_summary TITLE             every result and RESULT: PASS or FAIL (call it from the EXIT trap)

TJ_RESULTS=()
TJ_FAILED=0

tj_pass() { TJ_RESULTS+=("PASS  $*"); log "PASS: $*"; }
tj_fail() { TJ_RESULTS+=("FAIL  $*"); log "FAIL: $*"; TJ_FAILED=1; }

tj_check() {
  local what=$1 status=0
  shift
  # errexit does not apply inside a list's left side: the status is read whatever the options
  { "$@" 2>&1 | sed 's/^/    | /' >&2; status=${PIPESTATUS[0]}; } || true
  if ((status == 0)); then tj_pass "$what"; else tj_fail "$what (exit $status)"; fi
  return "$status"
}

tj_summary() {
  printf '\n== %s ==\n' "$1"
  printf '%s\n' "${TJ_RESULTS[@]}"
  if ((TJ_FAILED)); then printf 'RESULT: FAIL\n'; else printf 'RESULT: PASS\n'; fi
}
