# Sourced by test/scripts/test_fuzz.sh and scripts/fuzz.sh: builds the libFuzzer targets of
# test/fuzz/ with clang-14, ASan and UBSan in their own build directory, and runs them.
HAMERITT_ROOT="${HAMERITT_ROOT:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}"
FUZZ_BUILD_DIR="${HAMERITT_FUZZ_BUILD_DIR:-$HAMERITT_ROOT/build/fuzz}"
# Slowest first, so that the side-by-side runs end together.
FUZZ_TARGETS=(mesh manifest sim_config validator mission lod world path_csv spec)
# Any sanitizer report ends the run with a stack trace; leaks inside assimp are suppressed.
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:print_summary=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export LSAN_OPTIONS="suppressions=$HAMERITT_ROOT/test/fuzz/lsan.supp:print_suppressions=0"

fuzz_build() {
  CC=clang-14 CXX=clang++-14 cmake -S "$HAMERITT_ROOT/test/fuzz" -B "$FUZZ_BUILD_DIR" >/dev/null
  cmake --build "$FUZZ_BUILD_DIR" -j "${HAMERITT_JOBS:-$(nproc)}" >/dev/null
}

# fuzz_run TARGET WORKDIR ARGS...: fuzzes from the committed seed corpus (new inputs go to
# WORKDIR/corpus, crashes to WORKDIR/); prints libFuzzer's log to WORKDIR/log. ARGS come after
# the defaults, so that they override them (libFuzzer keeps the last value of a flag).
# FUZZ_BIN=NAME runs NAME_fuzzer on TARGET's corpus instead (mesh_ub: the UBSan-only mesh twin).
fuzz_run() {
  local target="$1" work="$2"
  shift 2
  mkdir -p "$work/corpus"
  "$FUZZ_BUILD_DIR/${FUZZ_BIN:-$target}_fuzzer" -timeout=10 -rss_limit_mb=2048 -max_len=200000 "$@" \
    -print_final_stats=1 -artifact_prefix="$work/" "$work/corpus" \
    "$HAMERITT_ROOT/test/fuzz/corpus/$target" >"$work/log" 2>&1
}

# fuzz_replay TARGET: runs every saved regression input of TARGET once; fails on any finding.
fuzz_replay() {
  local dir="$HAMERITT_ROOT/test/fuzz/regressions/$1"
  [[ -d "$dir" ]] || return 0
  local files=("$dir"/*)
  ((${#files[@]} > 0)) || return 0
  "$FUZZ_BUILD_DIR/${1}_fuzzer" "${files[@]}"
}
