#!/usr/bin/env bash
# libFuzzer with AddressSanitizer and UndefinedBehaviorSanitizer on every reader of outside
# input (test/fuzz/*_fuzzer.cpp): builds them with clang-14 in build/fuzz, replays the saved
# regression inputs (test/fuzz/regressions/<target>/), then fuzzes each target for 10,000
# executions from its seed corpus, deterministically (-seed=1), and for 300 more with inputs
# of up to 1 MiB (-max_len=1048576) from a seed of 100,000-deep nesting ("[[[...", "{"a":{...")
# so that depth and size are explored too. Any crash, hang (> 10 s), memory beyond 2 GB,
# sanitizer report or unexpected exception fails. Longer runs: scripts/fuzz.sh SECONDS.
# The mesh target is the exception: assimp fills a fresh 16 MiB buffer per import, which ASan
# maps anew each time (about 9 executions/s), so its 10,000 and 300 run on its UBSan-only twin
# (mesh_ub_fuzzer, glibc's allocator) and 2,000 more run with ASan, as two halves of 1,000
# (seeds 1 and 3) side by side.
set -euo pipefail
source "$(dirname "$0")/../../scripts/fuzz_common.sh"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

fuzz_build
# The targets run side by side, HAMERITT_JOBS (default: the number of cores) at a time; each
# one alone is deterministic, whatever runs beside it.
jobs="${HAMERITT_JOBS:-$(nproc)}"
# Runs, one per line: "NAME PARTS RUNS BINARY" (BINARY_fuzzer is the executable). The mesh target's
# 10,000 run on its UBSan-only twin; its ASan runs are two halves side by side, so that it does
# not hold the test command's serial tests back alone.
runs_of() {
  if [[ "$1" == mesh ]]; then
    printf '%s\n' "mesh_ub 1 10000 mesh_ub" "mesh 2 2000 mesh"
  else
    echo "$1 1 10000 $1"
  fi
}
# The binary for the large inputs: mesh's UBSan twin (300 imports of up to 1 MiB).
large_bin() { if [[ "$1" == mesh ]]; then echo mesh_ub; else echo "$1"; fi; }
for t in "${FUZZ_TARGETS[@]}"; do
  first=1
  while read -r name parts runs bin; do
    for ((i = 0; i < parts; i++)); do
      while (($(jobs -rp | wc -l) >= jobs)); do wait -n || true; done
      (
        rc=0
        FUZZ_BIN="$bin" fuzz_run "$t" "$work/$name.$i" -runs=$((runs / parts)) \
          -seed=$((1 + 2 * i)) || rc=$?
        echo "$rc" >"$work/$name.$i.rc"
        ((first == 1 && i == 0)) || exit 0
        rc=0
        fuzz_replay "$t" >"$work/$t.replay" 2>&1 || rc=$?
        echo "$rc" >"$work/$t.replay_rc"
        rc=0
        mkdir -p "$work/$t.large/corpus"
        /usr/bin/python3 -c 'import sys; n = 100000; d = sys.argv[1]
open(d + "/deep_arrays.json", "w").write("[" * n + "]" * n)
open(d + "/deep_objects.json", "w").write("{\"a\":" * n + "1" + "}" * n)' "$work/$t.large/corpus"
        FUZZ_BIN="$(large_bin "$t")" fuzz_run "$t" "$work/$t.large" -runs=300 -seed=2 \
          -max_len=1048576 || rc=$?
        echo "$rc" >"$work/$t.large_rc"
      ) </dev/null &
    done
    first=0
  done < <(runs_of "$t")
done
wait
failed=0
for t in "${FUZZ_TARGETS[@]}"; do
  if [[ "$(cat "$work/$t.replay_rc")" != 0 ]]; then
    echo "FAIL $t: a regression input fails again"; tail -40 "$work/$t.replay"; failed=1
  fi
  while read -r name parts runs bin; do
    total=0
    for ((i = 0; i < parts; i++)); do
      if [[ "$(cat "$work/$name.$i.rc")" != 0 ]]; then
        echo "FAIL $name: finding (log below)"; tail -60 "$work/$name.$i/log"; failed=1
        continue 2
      fi
      # The stats line proves the executions are real: "#10000 DONE cov: ... exec/s: ...".
      done_line="$(grep -E '^#[0-9]+[[:space:]]+DONE' "$work/$name.$i/log" | tail -1)"
      n="$(sed -E 's/^#([0-9]+).*/\1/' <<<"$done_line")"
      echo "$name part $i: $done_line"
      total=$((total + ${n:-0}))
    done
    if ((total < runs)); then
      echo "FAIL $name: $total executions, fewer than $runs"; failed=1
    fi
  done < <(runs_of "$t")
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
