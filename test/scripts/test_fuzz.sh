#!/usr/bin/env bash
# libFuzzer with AddressSanitizer and UndefinedBehaviorSanitizer on every reader of outside
# input (test/fuzz/*_fuzzer.cpp): builds them with clang-14 in build/fuzz, replays the saved
# regression inputs (test/fuzz/regressions/<target>/), then fuzzes each target for 10,000
# executions from its seed corpus, deterministically (-seed=1), and for 300 more with inputs
# of up to 1 MiB (-max_len=1048576) from a seed of 100,000-deep nesting ("[[[...", "{"a":{...")
# so that depth and size are explored too. Any crash, hang (> 10 s), memory beyond 2 GB,
# sanitizer report or unexpected exception fails. Longer runs: scripts/fuzz.sh SECONDS.
set -euo pipefail
source "$(dirname "$0")/../../scripts/fuzz_common.sh"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

fuzz_build
# The targets run side by side, HAMERITT_JOBS (default: the number of cores) at a time; each
# one alone is deterministic, whatever runs beside it.
jobs="${HAMERITT_JOBS:-$(nproc)}"
for t in "${FUZZ_TARGETS[@]}"; do
  while (($(jobs -rp | wc -l) >= jobs)); do wait -n || true; done
  (
    rc=0
    fuzz_replay "$t" >"$work/$t.replay" 2>&1 || rc=$?
    echo "$rc" >"$work/$t.replay_rc"
    rc=0
    fuzz_run "$t" "$work/$t" -runs=10000 -seed=1 || rc=$?
    echo "$rc" >"$work/$t.rc"
    rc=0
    mkdir -p "$work/$t.large/corpus"
    /usr/bin/python3 -c 'import sys; n = 100000; d = sys.argv[1]
open(d + "/deep_arrays.json", "w").write("[" * n + "]" * n)
open(d + "/deep_objects.json", "w").write("{\"a\":" * n + "1" + "}" * n)' "$work/$t.large/corpus"
    fuzz_run "$t" "$work/$t.large" -runs=300 -seed=2 -max_len=1048576 || rc=$?
    echo "$rc" >"$work/$t.large_rc"
  ) &
done
wait
failed=0
for t in "${FUZZ_TARGETS[@]}"; do
  if [[ "$(cat "$work/$t.replay_rc")" != 0 ]]; then
    echo "FAIL $t: a regression input fails again"; tail -40 "$work/$t.replay"; failed=1
  fi
  if [[ "$(cat "$work/$t.rc")" != 0 ]]; then
    echo "FAIL $t: finding (log below)"; tail -60 "$work/$t/log"; failed=1; continue
  fi
  # The stats line proves the executions are real: "#10000 DONE cov: ... exec/s: ...".
  done_line="$(grep -E '^#[0-9]+[[:space:]]+DONE' "$work/$t/log" | tail -1)"
  runs="$(sed -E 's/^#([0-9]+).*/\1/' <<<"$done_line")"
  echo "$t: $done_line"
  if [[ -z "$runs" ]] || ((runs < 10000)); then
    echo "FAIL $t: fewer than 10000 executions"; tail -20 "$work/$t/log"; failed=1
  fi
  if [[ "$(cat "$work/$t.large_rc")" != 0 ]]; then
    echo "FAIL $t: finding with inputs up to 1 MiB (log below)"; tail -60 "$work/$t.large/log"
    failed=1; continue
  fi
  done_line="$(grep -E '^#[0-9]+[[:space:]]+DONE' "$work/$t.large/log" | tail -1)"
  runs="$(sed -E 's/^#([0-9]+).*/\1/' <<<"$done_line")"
  echo "$t (inputs up to 1 MiB): $done_line"
  if [[ -z "$runs" ]] || ((runs < 300)); then
    echo "FAIL $t: fewer than 300 executions with inputs up to 1 MiB"; tail -20 "$work/$t.large/log"
    failed=1
  fi
done
echo "fuzz targets: ${#FUZZ_TARGETS[@]}, failed: $failed"
exit "$failed"
