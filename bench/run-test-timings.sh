#!/bin/bash
# run-test-timings.sh - the reaction and recovery times that functional tests measure and print
# but do not bound (a loaded machine stretches them; docs/performance.md, "Reaction times"):
# runs the tests --runs N times (default 3), alternately as the machine is (added_load=none) and
# with one busy loop per core at normal priority (added_load=busy: as compilers load a CI
# machine), and prints, per figure and load, the count, minimum, median and maximum of every
# number in the lines the tests print as "[ measured ]", "[ measure  ]" or "measure:". The tests
# run through ctest, so DDS stays in their private network namespaces and user-mode-linux.
#
#   bench/run-test-timings.sh [--build-dir DIR] [--runs N] [--tests REGEX]
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/.." && pwd)
build=$root/build runs=3
# The tests whose bounds on these times were dropped, and their neighbours that print more.
tests='^(ValveFaults\.|valve_faults_e2e_tests$|gateway_e2e_tests$|valvectl_end_to_end_tests$|socketcan_bench$|uml_sim_motion_physics$)'
while [ $# -gt 0 ]; do
  case $1 in
  --build-dir) build=$(cd "$2" && pwd) || exit 2; shift 2 ;;
  --runs) runs=$2; shift 2 ;;
  --tests) tests=$2; shift 2 ;;
  *) sed -n '10p' "${BASH_SOURCE[0]}" | sed 's/^# *//' >&2; exit 2 ;;
  esac
done

work=$(mktemp -d /tmp/teejet-test-timings.XXXXXX)
trap 'rm -rf "$work"' EXIT
failed=0
for run in $(seq 1 "$runs"); do
  for load in none busy; do
    added=()
    [ "$load" = busy ] && added=("$here/warm-cores" --load)
    echo "run $run, added_load=$load, load average $(cut -d' ' -f1-3 /proc/loadavg)" >&2
    "${added[@]}" ctest --test-dir "$build" -V -R "$tests" >"$work/$load.$run.log" 2>&1 || {
      echo "run-test-timings: a test failed (run $run, added_load=$load):" >&2
      grep -E "\*\*\*(Failed|Timeout)|Exception" "$work/$load.$run.log" >&2
      failed=1
    }
  done
done

python3 - "$work" <<'PY'
import glob, os, re, statistics, sys
number = re.compile(r"-?\d+(?:\.\d+)?")
figures = {}
for path in sorted(glob.glob(os.path.join(sys.argv[1], "*.log"))):
    load = os.path.basename(path).split(".")[0]
    for line in open(path, errors="replace"):
        line = re.sub(r"^\d+: ", "", line.rstrip())
        found = re.search(r"\[ measured? *\] *|^measure: *", line)
        if not found:
            continue
        text = line[found.end():]
        key = number.sub("#", text)
        values = figures.setdefault((key, load), [])
        values.append([float(v) for v in number.findall(text)])
for (key, load), rows in sorted(figures.items()):
    columns = list(zip(*[row for row in rows if len(row) == len(rows[0])]))
    stats = "; ".join(f"{min(c):g} / {statistics.median(c):g} / {max(c):g}" for c in columns)
    print(f"TIMING added_load={load} n={len(rows)} {key}  [min / median / max: {stats}]")
PY
exit "$failed"
