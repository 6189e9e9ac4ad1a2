#!/usr/bin/env bash
# The test suite under background load: BUSY processes spin on the CPU while the suite runs ROUNDS times in
# a row (`make test-loaded`, defaults 4 and 3). Every round must pass: no test may depend on the machine
# being idle. Prints each round's pytest summary and the load average at its end; exits non-zero if any
# round failed.
set -u
cd "$(dirname "$0")/.."
BUSY=${BUSY:-4}
ROUNDS=${ROUNDS:-3}
PY=${PY:-.venv/bin/python}
pids=()
for _ in $(seq "$BUSY"); do
  "$PY" -c 'while True: pass' &
  pids+=($!)
done
trap 'kill "${pids[@]}" 2>/dev/null' EXIT
failed=0
for round in $(seq "$ROUNDS"); do
  start=$(date +%s)
  summary=$("$PY" -m pytest -m "not slow" -n auto --dist loadfile -p no:cacheprovider -o addopts="" 2>&1 | tail -n 1)
  status=${PIPESTATUS[0]}
  echo "round $round/$ROUNDS with $BUSY busy processes: $summary ($(( $(date +%s) - start )) s, load $(cut -d' ' -f1-3 /proc/loadavg))"
  case "$summary" in *failed*|*error*) failed=1 ;; esac
  [ "$status" -eq 0 ] || failed=1
done
exit $failed
