#!/usr/bin/env bash
# Quick start, command 2: install, build, and run every test (gtest, script checks with outside
# validators, rostest) through ctest. Ends with "N passed, N failed".
source "$(dirname "$0")/common.sh"
install_deps
build
cmake --build "$BUILD_DIR" --target tests -j "$JOBS"
source_devel

cd "$BUILD_DIR"
set +e
ctest --output-on-failure -j "$JOBS" 2>&1 | tee "$BUILD_DIR/ctest.log"
rc=${PIPESTATUS[0]}
set -e
# Individual test cases from the gtest/rostest result files, for the closing line.
counts="$(/usr/bin/python3 - "$BUILD_DIR/test_results" <<'PY'
import sys, pathlib, xml.etree.ElementTree as ET
passed = failed = 0
for f in pathlib.Path(sys.argv[1]).rglob("*.xml"):
    try:
        root = ET.parse(f).getroot()
    except ET.ParseError:
        failed += 1
        continue
    for case in root.iter("testcase"):
        if case.find("failure") is not None or case.find("error") is not None:
            failed += 1
        elif case.find("skipped") is None:
            passed += 1
print(passed, failed)
PY
)"
read -r cases_passed cases_failed <<<"$counts"
tests_total="$(grep -Eo 'tests failed out of [0-9]+' "$BUILD_DIR/ctest.log" | grep -Eo '[0-9]+$' || echo 0)"
tests_failed="$(grep -Eo '[0-9]+ tests failed' "$BUILD_DIR/ctest.log" | grep -Eo '^[0-9]+' || echo 0)"
echo "ctest: $((tests_total - tests_failed)) of $tests_total test programs passed; test cases: $cases_passed passed, $cases_failed failed"
echo "$((tests_total - tests_failed)) passed, $tests_failed failed"
exit "$rc"
