#!/bin/bash
# run-soak.sh - the gateway over a long run at full rate (docs/performance.md, "Soak"):
# teejet-gateway --can sim:32 with every telemetry message at 0.1 s (bench/full-poll.yaml,
# ~2,600 frames/s), valves powered off and on at random (readdressing the others and going
# offline), an ECU reading every topic and moving valves at 20 commands/s; RSS, open fds, threads
# and CPU sampled every 10 s. Runs inside tests/netns/isolated: DDS stays on this host.
#
#   bench/run-soak.sh [--build-dir DIR] [--minutes M] [--settle-s S] [--compare-s S] [--churn-period-s S] [--every-s S] [--when-asked]
#
# --when-asked: skip (exit 77) unless TEEJET_SOAK_LONG=1 (tools/test --soak sets it), so that a
# plain `ctest` never starts the one-hour run.
#
# Prints the RESOURCES, RSS, *_SERIES (every sample), COMPARE (first vs last --compare-s),
# COMMANDS, REASON and SUBSCRIBER lines of gateway_latency resources. Exit status 0 when every
# command got exactly one final state and RSS (+1 MiB at most), fds and threads ended no higher
# than in the first span; 1 otherwise (the gateway's log is printed then).
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/.." && pwd)
build=$root/build minutes=10 settle_s=30 compare_s=300 churn_s=7 every_s=10 inside=0
while [ $# -gt 0 ]; do
  case $1 in
  --build-dir) build=$(cd "$2" && pwd) || exit 2; shift 2 ;;
  --minutes) minutes=$2; shift 2 ;;
  --settle-s) settle_s=$2; shift 2 ;;
  --compare-s) compare_s=$2; shift 2 ;;
  --churn-period-s) churn_s=$2; shift 2 ;;
  --every-s) every_s=$2; shift 2 ;;
  --when-asked)
    if [ "${TEEJET_SOAK_LONG:-0}" != 1 ]; then
      echo "SKIP: the long soak runs only when asked: tools/test --soak (TEEJET_SOAK_LONG=1)"
      exit 77
    fi
    shift ;;
  --inside) inside=1; shift ;; # internal: the half inside the namespace
  *) sed -n '8p' "${BASH_SOURCE[0]}" | sed 's/^# *//' >&2; exit 2 ;;
  esac
done
if [ "$inside" = 0 ]; then
  exec "$root/tests/netns/isolated" "${BASH_SOURCE[0]}" --inside --build-dir "$build" \
    --minutes "$minutes" --settle-s "$settle_s" --compare-s "$compare_s" \
    --churn-period-s "$churn_s" --every-s "$every_s"
fi

unset FASTDDS_DEFAULT_PROFILES_FILE # every program gets the profile with --profile
profile=$root/config/fastdds-loopback.xml
log=$(mktemp "${TMPDIR:-/tmp}/soak-gateway.XXXXXX")
config=$(mktemp "${TMPDIR:-/tmp}/soak-config.XXXXXX")
{
  cat "$here/full-poll.yaml"
  # 0: no churn (the simulator section is then left out, as in bench/full-poll.yaml).
  [ "$churn_s" = 0 ] || printf 'simulator:\n  churn_period_s: %s\n' "$churn_s"
} >"$config"
"$build/gateway/app/teejet-gateway" --can sim:32 -c "$config" --domain 90 \
  --profile "$profile" --log-level warn >"$log" 2>&1 &
gateway=$!
trap 'kill -TERM $gateway 2>/dev/null; wait $gateway 2>/dev/null; rm -f "$log" "$config"' EXIT
window_s=$(awk -v m="$minutes" 'BEGIN { print m * 60 }')
status=0
"$build/bench/gateway_latency" resources --label soak --pid "$gateway" --subscribe \
  --domain 90 --profile "$profile" --commands-per-second 20 --rss-every-s "$every_s" \
  --settle-s "$settle_s" --window-s "$window_s" --compare-s "$compare_s" --check || status=$?
if ((status != 0)); then
  echo "run-soak.sh: failed; the gateway's log:" >&2
  cat "$log" >&2
fi
exit "$status"
