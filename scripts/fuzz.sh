#!/usr/bin/env bash
# Longer fuzzing than the test command's 10,000 executions: every target of test/fuzz/ for
# SECONDS each (default 300), with ASan and UBSan. New interesting inputs are kept in
# build/fuzz/corpus/<target>/ (reused by the next run); a finding is saved as
# build/fuzz/findings/<target>/crash-* (or leak-*, timeout-*, oom-*): copy it to
# test/fuzz/regressions/<target>/ once fixed, so that the test command replays it.
#   scripts/fuzz.sh [SECONDS] [TARGET...]
set -euo pipefail
source "$(dirname "$0")/fuzz_common.sh"
seconds="${1:-300}"
shift || true
targets=("$@")
((${#targets[@]})) || targets=("${FUZZ_TARGETS[@]}")
fuzz_build
status=0
for t in "${targets[@]}"; do
  work="$FUZZ_BUILD_DIR/findings/$t"
  mkdir -p "$work" "$FUZZ_BUILD_DIR/corpus/$t"
  ln -sfn "$FUZZ_BUILD_DIR/corpus/$t" "$work/corpus"
  if fuzz_run "$t" "$work" -max_total_time="$seconds"; then
    echo "$t: $(grep -E '^#[0-9]+[[:space:]]+DONE' "$work/log" | tail -1)"
  else
    echo "$t: FINDING, see $work/log and $work/"; status=1
  fi
done
exit "$status"
