#!/usr/bin/env bash
# The threaded parts under ThreadSanitizer: builds test_threads in build/tsan (clang-14, -O1; the
# program exists only in a -DHAMERITT_SANITIZE=thread build, CMakeLists.txt) with the libraries it
# links, and runs it through the judge of scripts/sanitizers_common.sh (any report fails). It
# holds the gtests of the export's encoding pool, the TAK sender's thread and queue, the
# lock-step inbox and counters fed from many threads, and batch generation on several threads
# (--jobs). Negative control first: a data race in test/sanitizers/control.cpp, compiled the same
# way, must be reported and fail the judge. docs/RELIABILITY.md "Sanitizers" has the cost.
# The same clang-14 build also runs hameritt_generate through the golden-output check: the
# golden files are g++'s, so this shows that generation does not depend on the compiler (C++
# leaves the order of a call's arguments to it: see "Draw order" in generator.cpp), and it runs
# batch generation with --jobs 2 under TSan.
set -euo pipefail
source "$(dirname "$0")/../../scripts/sanitizers_common.sh"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

sanitizer_configure tsan
sanitizer_build tsan "${TSAN_TARGETS[@]}" >"$work/build.log" 2>&1 ||
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

# Compiler independence: clang-14's generator against the golden files of the g++ build (the
# check has its own negative control: a flipped byte, a missing and an extra file).
if HAMERITT_BIN_DIR="$bin" HAMERITT_GENERATE="$bin/hameritt_generate_sanitized" HAMERITT_SOURCE_DIR="$HAMERITT_ROOT" /usr/bin/python3 "$HAMERITT_ROOT/test/scripts/test_golden_outputs.py" \
  >"$work/golden.log" 2>&1 && ! grep -qE "$SANITIZER_REPORT_RE" "$work/golden.log"; then
  echo "clang-14 generation: $(tail -1 "$work/golden.log")"
else
  echo "FAIL: clang-14 (TSan) generation differs from the golden files or was reported:"
  { grep -E "FAIL|$SANITIZER_REPORT_RE" "$work/golden.log" || tail -5 "$work/golden.log"; } | head -20
  failed=1
fi
# rosrun searches the whole package directory, build/tsan included: a second hameritt_generate
# there makes `rosrun hameritt hameritt_generate` ask which one to run and, with no terminal, run
# none (the mission tests failed on it while the test command's background build had made the
# tree). The tree's programs carry the suffix _sanitized; with the tree built, rosrun must still
# find exactly one program and run it. The devel space is the normal build's again here.
if [[ -x "$bin/hameritt_generate" ]]; then
  echo "FAIL: the TSan tree has a program named hameritt_generate"; failed=1
fi
if out="$(set +u; source "$HAMERITT_ROOT/build/devel/setup.bash" && cd "$work" &&
  rosrun hameritt hameritt_generate --help </dev/null 2>&1)"; then
  echo "rosrun hameritt hameritt_generate with the TSan tree built: one program, --help exit 0"
else
  echo "FAIL: rosrun hameritt hameritt_generate with the TSan tree built:"; head -8 <<<"$out"
  failed=1
fi
exit "$failed"
