#!/usr/bin/env bash
# The threaded parts under ThreadSanitizer: builds test_threads in build/tsan (clang-14, -O1; the
# program exists only in a -DHAMERITT_SANITIZE=thread build, CMakeLists.txt) with the libraries it
# links, and runs it through the judge of scripts/sanitizers_common.sh (any report fails). It
# holds the gtests of the export's encoding pool, the TAK sender's thread and queue, the
# lock-step inbox and counters fed from many threads, and batch generation on several threads
# (--jobs). Negative control first: a data race in test/sanitizers/control.cpp, compiled the same
# way, must be reported and fail the judge. docs/RELIABILITY.md "Sanitizers" has the cost.
set -euo pipefail
source "$(dirname "$0")/../../scripts/sanitizers_common.sh"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

sanitizer_configure tsan
sanitizer_build tsan test_sanitizer_control test_threads >"$work/build.log" 2>&1 ||
  { tail -40 "$work/build.log"; exit 1; }
sanitizer_source_devel tsan
bin="$(sanitizer_build_dir tsan)/devel/lib/hameritt"

failed=0
sanitizer_control_check tsan data-race "WARNING: ThreadSanitizer: data race" || failed=1
sanitizer_run "$work/control_none.log" "$bin/sanitizer_control" none ||
  { echo "FAIL: the negative control without a fault failed the judge"; failed=1; }

sanitizer_run "$work/test_threads.log" "$bin/test_threads" || { failed=1; tail -80 "$work/test_threads.log"; }
n="$(sanitizer_gtest_count "$work/test_threads.log")"
# Every listed test passed, and every threaded part has its tests in the program.
mapfile -t listed < <("$bin/test_threads" --gtest_list_tests | grep -E '^[A-Za-z][A-Za-z0-9_]*\.$')
total="$("$bin/test_threads" --gtest_list_tests | grep -cE '^  ' || true)"
echo "tsan: test_threads passed ${n:-0} of $total tests (suites: ${listed[*]})"
if [[ "${n:-0}" != "$total" ]]; then echo "FAIL: not every test passed"; failed=1; fi
for suite in EncodePool. TakSender. LockstepInbox. PublicationCounter. GeneratorReuseTest. BatchSliceTest.; do
  printf '%s\n' "${listed[@]}" | grep -qx "$suite" || { echo "FAIL: no $suite tests"; failed=1; }
done
exit "$failed"
