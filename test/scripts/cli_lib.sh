# Shared by the command-line test scripts (source it): the source and binary directories, a
# temporary directory $T removed on exit, pass/fail counters, ok/bad, expect, and finish.
# Usage: source "$(dirname "$0")/cli_lib.sh" NAME   (NAME names the temporary directory)
set -u
BIN="${HAMERITT_BIN_DIR:?}"
SRC="${HAMERITT_SOURCE_DIR:?}"
T="$(mktemp -d "/tmp/hameritt_${1:?}.XXXXXX")"
trap 'rm -rf "$T"' EXIT
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }

# expect CODE PATTERN CMD...: the command exits with CODE and its stderr matches PATTERN.
expect() {
  local code="$1" pattern="$2"
  shift 2
  local err rc
  err="$("$@" 2>&1 >/dev/null)"
  rc=$?
  if [[ $rc -ne $code ]]; then
    bad "'$*' exited $rc, expected $code: $err"
  elif [[ -n "$pattern" && ! "$err" =~ $pattern ]]; then
    bad "'$*' stderr does not match /$pattern/: $err"
  else
    ok
  fi
}
