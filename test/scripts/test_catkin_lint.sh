#!/usr/bin/env bash
# catkin_lint (Debian catkin-lint) on the package at its default level (-W1: errors and
# warnings), strict: any error or warning fails. The executable scripts it is told to ignore
# (CMakeLists.txt: "#catkin_lint: ignore uninstalled_script") must be exactly the checkout's own
# tools named below, so a new user-facing script that is not installed still fails here.
# Negative controls, on scratch copies of the package: a dependency removed from package.xml,
# a node left out of the install rules, and an uninstalled executable script must each be
# reported.
source "$(dirname "$0")/cli_lib.sh" catkin_lint

if ! command -v catkin_lint >/dev/null 2>&1; then
  echo "test_catkin_lint: catkin_lint is not installed (Debian package catkin-lint)"
  exit 1
fi

# Checkout tools: build, test, fuzz, redraw, benchmark a source tree; not installed.
CHECKOUT_TOOLS="bench/bench_mission.py
scripts/common.sh
scripts/fuzz.sh
scripts/make_city_images.sh
scripts/make_default_scenario.sh
scripts/make_meshes.py
scripts/make_render_images.sh
scripts/run_main.sh
scripts/run_sanitizers.sh"

# lint DIR OUT: catkin_lint -W1 --strict on DIR (any error or warning fails); returns its code.
lint() {
  catkin_lint -W1 --strict "$1" >"$2" 2>&1
}
# uninstalled_scripts DIR: the executable scripts catkin_lint finds not installed in DIR, the
# ones it was told to ignore included, sorted.
uninstalled_scripts() {
  catkin_lint -W1 --show-ignored "$1" 2>&1 |
    sed -n "s/^hameritt: warning: file '\(.*\)' is executable but not installed$/\1/p" | sort
}

# ------------------------------------------------------------------ the package as it is
lint "$SRC" "$T/clean.out"
rc=$?
[[ $rc -eq 0 ]] && ok || bad "catkin_lint -W1 --strict exited $rc: $(cat "$T/clean.out")"
grep -q "checked 1 packages and found 0 problems" "$T/clean.out" && ok ||
  bad "catkin_lint does not say 0 problems: $(cat "$T/clean.out")"
grep -Eq "^hameritt: .*(error|warning):" "$T/clean.out" && bad "errors or warnings: $(cat "$T/clean.out")" || ok

got="$(uninstalled_scripts "$SRC")"
[[ "$got" == "$CHECKOUT_TOOLS" ]] && ok ||
  bad "uninstalled executable scripts differ from the checkout tools: got
$got
expected
$CHECKOUT_TOOLS"

# ------------------------------------------------------------------ negative controls
# scratch NAME [DIR...]: a scratch copy of the package: package.xml, CMakeLists.txt and the
# named directories copied, every other top-level entry linked (catkin_lint does not walk into
# a linked directory).
scratch() {
  local dir="$T/$1"
  shift
  mkdir -p "$dir"
  local e
  for e in "$SRC"/*; do
    case "$(basename "$e")" in build | build-workspace | package.xml | CMakeLists.txt) continue ;; esac
    ln -s "$e" "$dir/$(basename "$e")"
  done
  cp "$SRC/package.xml" "$SRC/CMakeLists.txt" "$dir/"
  for e in "$@"; do
    rm "$dir/$e"
    cp -a "$SRC/$e" "$dir/$e"
  done
  echo "$dir"
}

# The scratch copy unchanged is clean: the controls below fail for their change alone.
d="$(scratch unchanged)"
lint "$d" "$T/unchanged.out" && ok || bad "the unchanged scratch copy is not clean: $(cat "$T/unchanged.out")"

# 1. roscpp removed from package.xml: find_package(catkin COMPONENTS roscpp) lacks its depend.
d="$(scratch no_roscpp)"
sed -i '\|<depend>roscpp</depend>|d' "$d/package.xml"
grep -q "<depend>roscpp</depend>" "$d/package.xml" && bad "roscpp not removed" || ok
lint "$d" "$T/no_roscpp.out" && bad "a package.xml without roscpp passed" || ok
grep -Eq "^hameritt: .*error: .*roscpp" "$T/no_roscpp.out" && ok ||
  bad "no error names roscpp: $(cat "$T/no_roscpp.out")"

# 2. The simulator node left out of the install rules.
d="$(scratch no_install)"
sed -i '/^          scenario_generator simulator planner/s/ simulator / /' "$d/CMakeLists.txt"
cmp -s "$SRC/CMakeLists.txt" "$d/CMakeLists.txt" && bad "simulator not removed from install()" || ok
lint "$d" "$T/no_install.out" && bad "an uninstalled node passed" || ok
grep -q "target 'simulator' is not installed" "$T/no_install.out" && ok ||
  bad "the uninstalled node is not named: $(cat "$T/no_install.out")"

# 3. A new executable script a user would run, not installed.
d="$(scratch new_script scripts bench)"
mkdir "$d/tools"
printf '#!/usr/bin/python3\nprint("hi")\n' >"$d/tools/my_tool.py"
chmod +x "$d/tools/my_tool.py"
got="$(uninstalled_scripts "$d")"
expected="$(printf '%s\ntools/my_tool.py\n' "$CHECKOUT_TOOLS" | sort)"
[[ "$got" == "$expected" ]] && ok || bad "the uninstalled scripts are not the checkout tools and the new one: $got"

echo "test_catkin_lint: $pass passed, $fail failed"
[[ $fail -eq 0 ]]
