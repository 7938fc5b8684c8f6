#!/usr/bin/env bash
# The whole gtest suite under AddressSanitizer (with LeakSanitizer) and UndefinedBehaviorSanitizer:
# builds the libraries and the gtest programs with -DHAMERITT_SANITIZE=address,undefined in
# build/asan (separate from build/), then runs every gtest program. Any sanitizer report fails
# the program (halt_on_error, no recovery). Too slow for the test command on 2 cores (a full
# instrumented build), so it is run on its own: docs/RELIABILITY.md has the last figures.
#   scripts/run_sanitizers.sh [GTEST_PROGRAM...]   (default: every test_* gtest program)
source "$(dirname "$0")/common.sh"
install_deps
ASAN_BUILD_DIR="${HAMERITT_ASAN_BUILD_DIR:-$HAMERITT_ROOT/build/asan}"
cmake -S "$HAMERITT_ROOT" -B "$ASAN_BUILD_DIR" -DCMAKE_BUILD_TYPE=Release \
  -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=ON \
  -DHAMERITT_SANITIZE=address,undefined "${CCACHE_ARGS[@]}" >/dev/null
programs=("$@")
if ((${#programs[@]} == 0)); then
  programs=(test_geometry test_scenario test_map test_sim test_planning test_render test_adk
            test_clients test_ros_conversions)
fi
cmake --build "$ASAN_BUILD_DIR" --target "${programs[@]}" -j "$JOBS"
# Leaks inside Mesa's llvmpipe/EGL driver are not ours: test/sanitizers/lsan.supp, documented.
export ASAN_OPTIONS="detect_leaks=1:halt_on_error=1:abort_on_error=0:print_summary=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export LSAN_OPTIONS="suppressions=$HAMERITT_ROOT/test/sanitizers/lsan.supp:print_suppressions=1"
set +u
# shellcheck disable=SC1091
source "$ASAN_BUILD_DIR/devel/setup.bash"
set -u
cd "$HAMERITT_ROOT"
# True when the only report in the log is LeakSanitizer's and every leaked block was allocated
# directly from an unloaded module: Mesa's driver is dlclosed when the EGL display is
# terminated, so its leaks have no symbols and cannot be named in a suppression. Any test
# failure, any other sanitizer report, or any leak with a named frame still fails.
third_party_leaks_only() {
  grep -q 'ERROR: LeakSanitizer' "$1" || return 1
  grep -qE 'runtime error|ERROR: AddressSanitizer|\[  FAILED  \]' "$1" && return 1
  # Frame #1 (the allocation's caller) of every leak.
  ! grep -A2 -E '^(Direct|Indirect) leak of' "$1" | grep -E '^    #1 ' | grep -qv '(<unknown module>)'
}
passed=0
failed=0
for p in "${programs[@]}"; do
  log="$ASAN_BUILD_DIR/$p.log"
  if "$ASAN_BUILD_DIR/devel/lib/hameritt/$p" >"$log" 2>&1; then
    passed=$((passed + 1))
    echo "ok   $p: $(grep -E '^\[  PASSED  \]' "$log" | tail -1)"
  elif third_party_leaks_only "$log"; then
    passed=$((passed + 1))
    echo "ok   $p: $(grep -E '^\[  PASSED  \]' "$log" | tail -1); LeakSanitizer: only leaks" \
      "allocated from an unloaded module (Mesa's EGL/DRI driver, dlclosed at eglTerminate)"
  else
    failed=$((failed + 1))
    echo "FAIL $p (log: $log)"
    grep -E 'ERROR: |SUMMARY: |runtime error|FAILED' "$log" | head -20
  fi
done
echo "sanitizers: $passed passed, $failed failed"
((failed == 0))
