#!/usr/bin/env bash
# The gtest programs under a sanitizer, by hand (the test command runs the same builds and
# judge as ctest script_test_sanitizers_asan and script_test_sanitizers_tsan):
#   scripts/run_sanitizers.sh [asan|tsan] [GTEST_PROGRAM...]
# asan (default): AddressSanitizer with LeakSanitizer and UndefinedBehaviorSanitizer in
# build/asan, every gtest program unless some are named. tsan: ThreadSanitizer in build/tsan,
# test_threads (the threaded parts) unless programs are named. Builds, flags, runtime options and
# the judge are scripts/sanitizers_common.sh's; any report fails the program.
source "$(dirname "$0")/sanitizers_common.sh"
install_deps
kind=asan
if [[ "${1:-}" == asan || "${1:-}" == tsan ]]; then
  kind="$1"
  shift
fi
sanitizer_configure "$kind"
programs=("$@")
if ((${#programs[@]} == 0)); then
  if [[ "$kind" == tsan ]]; then
    programs=(test_threads)
  else
    mapfile -t programs < <(sanitizer_gtests asan)
  fi
fi
sanitizer_build "$kind" "${programs[@]}"
sanitizer_source_devel "$kind"
dir="$(sanitizer_build_dir "$kind")"
passed=0
failed=0
for p in "${programs[@]}"; do
  if sanitizer_run "$dir/$p.log" "$dir/devel/lib/hameritt/$p"; then
    passed=$((passed + 1))
  else
    failed=$((failed + 1))
  fi
done
echo "sanitizers ($kind): $passed passed, $failed failed"
((failed == 0))
