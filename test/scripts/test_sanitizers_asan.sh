#!/usr/bin/env bash
# The gtest programs under AddressSanitizer (with LeakSanitizer) and UndefinedBehaviorSanitizer:
# builds them in build/asan (clang-14, -O1, only the libraries they link) and runs each through
# the judge of scripts/sanitizers_common.sh (any report fails), two at a time, the slowest first.
# Negative control first: test/sanitizers/control.cpp, compiled the same way, must be reported
# and fail the judge for each fault (heap overflow, use after free, signed overflow, a leak from
# our code), and pass without one. docs/RELIABILITY.md "Sanitizers" has the cost.
set -euo pipefail
source "$(dirname "$0")/../../scripts/sanitizers_common.sh"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

SECONDS=0
sanitizer_configure asan
echo "configured: ${SECONDS} s (with the wait for a background build of build/asan)"
# The gtest programs (sanitizers_common.sh: asan_programs).
mapfile -t programs < <(asan_programs)
if [[ -z "${HAMERITT_ASAN_PROGRAMS:-}" ]]; then
  # The list comes from the build; it must hold at least the ten programs known today.
  ((${#programs[@]} >= 10)) || { echo "FAIL: fewer than 10 gtest programs: ${programs[*]}"; exit 1; }
fi
echo "gtest programs: ${#programs[@]} (${programs[*]})"
sanitizer_build asan test_sanitizer_control "${programs[@]}" >"$work/build.log" 2>&1 ||
  { tail -40 "$work/build.log"; exit 1; }
echo "built: ${SECONDS} s"
sanitizer_source_devel asan
bin="$(sanitizer_build_dir asan)/devel/lib/hameritt"

failed=0
sanitizer_control_check asan heap-buffer-overflow "ERROR: AddressSanitizer: heap-buffer-overflow" || failed=1
sanitizer_control_check asan use-after-free "ERROR: AddressSanitizer: heap-use-after-free" || failed=1
sanitizer_control_check asan signed-integer-overflow "runtime error: signed integer overflow" || failed=1
# A leak from our code fails even though Mesa's leaks are let through.
sanitizer_control_check asan leak "ERROR: LeakSanitizer: detected memory leaks" || failed=1
sanitizer_run "$work/control_none.log" "$bin/sanitizer_control" none ||
  { echo "FAIL: the negative control without a fault failed the judge"; failed=1; }

# The gtest programs, HAMERITT_JOBS (default: the number of cores) at a time, the slowest first
# (longest processing time first), so that no core idles at the end while the last long one
# runs alone. The list is by the seconds each took (2-core VM, 2026-11-27, with the slowest
# tests' fewer repetitions of test/sanitized.h: scenario 285, generation 187, render 84 (479 s
# more before), clients 71, planning 45, map 26, sim 11, the rest under 10); a program not
# listed comes after them. Each program's seconds are printed.
slowest=(test_scenario test_generation test_render test_clients test_planning test_map test_sim)
order=()
for p in "${slowest[@]}"; do
  if [[ " ${programs[*]} " == *" $p "* ]]; then order+=("$p"); fi
done
for p in "${programs[@]}"; do
  if [[ " ${slowest[*]} " != *" $p "* ]]; then order+=("$p"); fi
done
jobs="${HAMERITT_JOBS:-$(nproc)}"
for p in "${order[@]}"; do
  while (($(jobs -rp | wc -l) >= jobs)); do wait -n || true; done
  (
    rc=0
    start=$SECONDS
    sanitizer_run "$work/$p.log" "$bin/$p" >"$work/$p.verdict" || rc=$?
    echo "$rc" >"$work/$p.rc"
    echo "$p: $((SECONDS - start)) s" >"$work/$p.time"
  ) &
done
wait
tests=0
for p in "${programs[@]}"; do
  cat "$work/$p.verdict" "$work/$p.time"
  if [[ "$(cat "$work/$p.rc")" != 0 ]]; then
    failed=1
    tail -60 "$work/$p.log"
    continue
  fi
  n="$(sanitizer_gtest_count "$work/$p.log")"
  if [[ -z "$n" ]] || ((n < 1)); then
    echo "FAIL $p: no test ran"; failed=1; continue
  fi
  tests=$((tests + n))
done
echo "asan+ubsan: ${#programs[@]} gtest programs, $tests tests, failed: $failed (build and runs: $SECONDS s)"
exit "$failed"
