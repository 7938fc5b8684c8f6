# Sourced by scripts/run_sanitizers.sh and test/scripts/test_sanitizers_{asan,tsan}.sh: the
# sanitizer builds (one place for their flags, directories and runtime options) and the judge that
# decides whether a program run under a sanitizer passed.
#   asan: AddressSanitizer + LeakSanitizer + UndefinedBehaviorSanitizer, build/asan
#   tsan: ThreadSanitizer, build/tsan
# Each is the top-level project configured with -DHAMERITT_SANITIZE (CMakeLists.txt
# adds -fsanitize=..., -fno-sanitize-recover=all and -O1), built only for the targets asked for:
# never the nodes, tools or messages that no gtest program links.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

sanitizer_flags() {
  case "$1" in
    asan) echo "address,undefined" ;;
    tsan) echo "thread" ;;
    *) echo "sanitizer_flags: unknown sanitizer '$1' (asan or tsan)" >&2; return 2 ;;
  esac
}

sanitizer_build_dir() {
  local var="HAMERITT_${1^^}_BUILD_DIR"
  echo "${!var:-$HAMERITT_ROOT/build/$1}"
}

# sanitizer_configure asan|tsan: configures the build directory, both with clang-14 (about half
# the compile time of g++ at the same -O1: generator.cpp with ASan+UBSan takes 16 s of CPU
# against 32 s). Generation does not depend on the compiler (docs/RELIABILITY.md, "Golden
# outputs"), so the gtests that pin the shipped scenario's values pass under either. A build
# directory configured with another compiler (an older checkout's g++ tree) is configured anew.
sanitizer_configure() {
  local flags dir cc=clang-14 cxx=clang++-14
  flags="$(sanitizer_flags "$1")"
  dir="$(sanitizer_build_dir "$1")"
  (
    sanitizer_lock "$1"
    if [[ -f "$dir/CMakeCache.txt" ]] &&
      ! grep -q "^CMAKE_CXX_COMPILER:[A-Z]*=.*$cxx\$" "$dir/CMakeCache.txt"; then
      rm -rf "$dir/CMakeCache.txt" "$dir/CMakeFiles"
    fi
    CC=$cc CXX=$cxx cmake -S "$HAMERITT_ROOT" -B "$dir" -DCMAKE_BUILD_TYPE=Release \
      -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=ON \
      -DHAMERITT_SANITIZE="$flags" "${CCACHE_ARGS[@]}" >/dev/null
    # A tree's programs carry the suffix _sanitized (CMakeLists.txt: rosrun searches the whole
    # package directory); a program an older checkout built here under its plain name goes.
    if [[ -d "$dir/devel/lib/hameritt" ]]; then
      find "$dir/devel/lib/hameritt" -maxdepth 1 -type f ! -name 'test_*' ! -name '*_sanitized' \
        ! -name sanitizer_control -delete
    fi
  )
}

# sanitizer_lock asan|tsan: in a subshell, waits until no other configure or build of that
# build directory runs (the test command's background build, below), then holds the lock until
# the subshell ends.
sanitizer_lock() {
  local dir
  dir="$(sanitizer_build_dir "$1")"
  mkdir -p "$(dirname "$dir")"
  exec 9>"$dir.lock"
  flock 9
}

# sanitizer_gtests asan|tsan: every gtest program of the configured build (catkin_add_gtest), so
# that a new one is never left out.
sanitizer_gtests() {
  (cd "$(sanitizer_build_dir "$1")" && ctest -N) |
    sed -nE 's/.*_ctest_hameritt_gtest_(test_[A-Za-z0-9_]+)$/\1/p' | sort -u
}

# sanitizer_build asan|tsan TARGET...: builds the targets (and only what they link).
sanitizer_build() {
  local dir kind="$1"
  dir="$(sanitizer_build_dir "$1")"
  shift
  (
    sanitizer_lock "$kind"
    cmake --build "$dir" -j "$JOBS" --target "$@"
  )
}

# The targets of the sanitizer tests. asan: the negative control and every gtest program of the
# configured build (so that a new one is never left out) but test_ros_conversions: its five
# tests of the ROS message conversions would need the whole instrumented ROS layer and the
# generated messages (sixteen ROS sources, the heaviest to compile) and do not fit the test
# command's budget; scripts/run_sanitizers.sh runs it by hand. HAMERITT_ASAN_PROGRAMS names
# another list. tsan: the control, test_threads and hameritt_generate.
asan_programs() {
  if [[ -n "${HAMERITT_ASAN_PROGRAMS:-}" ]]; then
    tr ' ' '\n' <<<"$HAMERITT_ASAN_PROGRAMS" | grep -v '^$'
  else
    sanitizer_gtests asan | grep -vx test_ros_conversions
  fi
}
TSAN_TARGETS=(test_sanitizer_control test_threads hameritt_generate)

# sanitizer_prebuild: the test command (scripts/run_tests.sh) runs this in the background at the
# lowest priority (nice 19) while ctest runs the other tests: the instrumented builds of both
# sanitizer tests, which ctest runs last. The tests of the serial phase (whole missions,
# rostests) leave a core idle much of the time; the builds take that time and little else.
# Each sanitizer test then configures and builds again under the same lock: it waits for the
# background build of its tree to end and finds its targets built (or finishes them).
sanitizer_prebuild() {
  local programs
  echo "sanitizer prebuild: start $(date +%T)"
  sanitizer_configure asan
  mapfile -t programs < <(asan_programs)
  sanitizer_build asan test_sanitizer_control "${programs[@]}" && echo "asan built $(date +%T)"
  sanitizer_configure tsan
  sanitizer_build tsan "${TSAN_TARGETS[@]}" && echo "tsan built $(date +%T)"
}

# Runtime options: every report ends the program with a non-zero status (no recovery).
export ASAN_OPTIONS="detect_leaks=1:halt_on_error=1:abort_on_error=0:print_summary=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
# Leaks inside Mesa's llvmpipe/EGL driver are not ours: test/sanitizers/lsan.supp, documented.
export LSAN_OPTIONS="suppressions=$HAMERITT_ROOT/test/sanitizers/lsan.supp:print_suppressions=1"
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1"
if [[ -x /usr/lib/llvm-14/bin/llvm-symbolizer ]]; then
  export ASAN_SYMBOLIZER_PATH=/usr/lib/llvm-14/bin/llvm-symbolizer
  export TSAN_OPTIONS="$TSAN_OPTIONS:external_symbolizer_path=$ASAN_SYMBOLIZER_PATH"
fi

# The reports a sanitizer writes; any of them in a log fails the run.
SANITIZER_REPORT_RE='ERROR: AddressSanitizer|ERROR: LeakSanitizer|runtime error:|WARNING: ThreadSanitizer|ThreadSanitizer: (reported|unexpected)'

# True when the only report in the log is LeakSanitizer's and every leaked block was allocated
# directly from an unloaded module: Mesa's driver is dlclosed when the EGL display is
# terminated, so its leaks have no symbols and cannot be named in a suppression. Any test
# failure, any other sanitizer report, or any leak with a named frame still fails.
third_party_leaks_only() {
  grep -q 'ERROR: LeakSanitizer' "$1" || return 1
  grep -qE 'runtime error|ERROR: AddressSanitizer|ThreadSanitizer|\[  FAILED  \]' "$1" && return 1
  # Frame #1 (the allocation's caller) of every leak.
  ! grep -A2 -E '^(Direct|Indirect) leak of' "$1" | grep -E '^    #1 ' | grep -qv '(<unknown module>)'
}

# sanitizer_judge LOG STATUS: 0 when a program that exited with STATUS and wrote LOG passed: it
# exited 0 with no sanitizer report, or its only report is a leak of the unloaded Mesa driver.
# Prints one line: "ok ..." or "FAIL ..." with the reports.
sanitizer_judge() {
  local log="$1" status="$2" name
  name="$(basename "$log" .log)"
  if [[ "$status" == 0 ]] && ! grep -qE "$SANITIZER_REPORT_RE" "$log"; then
    echo "ok   $name: $(grep -E '^\[  PASSED  \]' "$log" | tail -1)"
    return 0
  fi
  if third_party_leaks_only "$log"; then
    echo "ok   $name: $(grep -E '^\[  PASSED  \]' "$log" | tail -1); LeakSanitizer: only leaks" \
      "allocated from an unloaded module (Mesa's EGL/DRI driver, dlclosed at eglTerminate)"
    return 0
  fi
  echo "FAIL $name (exit status $status, log: $log)"
  grep -E "$SANITIZER_REPORT_RE|SUMMARY: |FAILED" "$log" | head -20
  return 1
}

# sanitizer_run LOG PROGRAM ARGS...: runs the program from the source tree (where the gtest
# programs expect to run), its output in LOG, and judges it.
sanitizer_run() {
  local log="$1" status=0
  shift
  (cd "$HAMERITT_ROOT" && "$@") >"$log" 2>&1 || status=$?
  sanitizer_judge "$log" "$status"
}

# sanitizer_source_devel asan|tsan: the build's devel space (paths of its own binaries).
sanitizer_source_devel() {
  set +u
  # shellcheck disable=SC1091
  source "$(sanitizer_build_dir "$1")/devel/setup.bash"
  set -u
}

# sanitizer_control_check asan|tsan FAULT REPORT: the negative control. Runs the deliberate
# fault FAULT of sanitizer_control (test/sanitizers/control.cpp, built with the same flags)
# through the judge: 0 when the report REPORT is in its log and the judge failed the run.
sanitizer_control_check() {
  local bin log
  bin="$(sanitizer_build_dir "$1")/devel/lib/hameritt/sanitizer_control"
  log="$(mktemp)"
  if sanitizer_run "$log" "$bin" "$2" >/dev/null; then
    echo "FAIL negative control $2: the judge passed it"
  elif ! grep -q "$3" "$log"; then
    echo "FAIL negative control $2: no '$3' report"
    tail -20 "$log"
  else
    echo "negative control $2: reported ('$3') and failed, as it must"
    rm -f "$log"
    return 0
  fi
  rm -f "$log"
  return 1
}

# sanitizer_gtest_count LOG: how many tests the gtest program of LOG passed (empty if none).
sanitizer_gtest_count() {
  sed -nE 's/^\[  PASSED  \] ([0-9]+) tests?\..*/\1/p' "$1" | tail -1
}
