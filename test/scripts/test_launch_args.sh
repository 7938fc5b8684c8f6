#!/bin/bash
# Every argument of every launch/*.launch file carries a doc (`roslaunch --ros-args` prints no
# "undocumented"), and the only required argument is record.launch's output_dir (an argument
# with an empty default is listed as required: `tak` and the like default to a word meaning off).
# Negative control: a launch file with an undocumented argument and an empty default is caught.
set -euo pipefail
export PATH="/usr/bin:/bin:$PATH"
src="${HAMERITT_SOURCE_DIR:?}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fails=0
check() {  # check FILE ALLOWED_REQUIRED: prints what is wrong, returns 1 if anything is
  local out bad=0
  if ! out="$(roslaunch --ros-args "$1" 2>&1)"; then echo "  $1: roslaunch --ros-args failed: $out"; return 1; fi
  if grep -q "undocumented" <<<"$out"; then
    echo "  $(basename "$1"): undocumented: $(grep undocumented <<<"$out" | sed 's/:.*//' | tr -d ' ' | tr '\n' ' ')"; bad=1
  fi
  local required
  required="$(awk '/^Required Arguments:/{r=1;next} /^Optional Arguments:/{r=0} r{sub(/:.*/,"");gsub(/ /,"");print}' <<<"$out" | tr '\n' ' ')"
  if [[ "$required" != "$2" ]]; then echo "  $(basename "$1"): required arguments '$required', expected '$2'"; bad=1; fi
  return $bad
}
n=0
for f in "$src"/launch/*.launch; do
  n=$((n + 1))
  expected=""
  [[ "$(basename "$f")" == record.launch ]] && expected="output_dir "
  check "$f" "$expected" || fails=$((fails + 1))
done
echo "launch files checked: $n, with problems: $fails"
cat >"$tmp/bad.launch" <<'XML'
<launch>
  <arg name="documented" default="1" doc="A documented argument."/>
  <arg name="endpoint" default=""/>
</launch>
XML
if check "$tmp/bad.launch" "" >"$tmp/neg.txt"; then
  echo "FAIL: negative control: an undocumented, empty-default argument was not caught"; exit 1
fi
grep -q "undocumented: endpoint" "$tmp/neg.txt" && grep -q "required arguments 'endpoint '" "$tmp/neg.txt" || {
  echo "FAIL: negative control: unexpected report:"; cat "$tmp/neg.txt"; exit 1; }
echo "negative control caught: $(tr '\n' ';' <"$tmp/neg.txt")"
if ((n < 8 || fails > 0)); then echo "FAIL: $fails of $n launch files"; exit 1; fi
echo "PASS: every argument of the $n launch files is documented; only record.launch requires one"
