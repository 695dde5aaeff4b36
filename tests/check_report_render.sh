#!/usr/bin/env bash
# The bench report in CI size, end to end: `meshlight bench report --quick`
# must write DIR/index.html whose every picture and link points at a file it
# wrote, and headless Chromium must render the page into a screenshot that is
# not blank. Speed is reported by the benches, never asserted here.
#
# usage: check_report_render.sh MESHLIGHT OUT_DIR
# Exits 77 (ctest: skipped) when Chromium is not installed; set CHROMIUM to
# use another binary.
set -euo pipefail

meshlight=$1
out=$2
chromium=${CHROMIUM:-$(command -v chromium || command -v chromium-browser || true)}

rm -rf "$out"
mkdir -p "$out"
"$meshlight" bench report --quick --out "$out/report"
index="$out/report/index.html"
[ -s "$index" ] || { echo "FAIL: $index not written"; exit 1; }

# Every src and href but in-page anchors: relative, and an existing file.
refs=$(grep -o '\(src\|href\)="[^"#][^"]*"' "$index" | sed 's/^[a-z]*="//; s/"$//; s/&amp;/\&/g')
images=$(grep -c '<img ' "$index" || true)
csvs=$(printf '%s\n' "$refs" | grep -c '\.csv$' || true)
echo "index.html: $images images, $csvs CSV links"
[ "$images" -ge 1 ] || { echo "FAIL: no <img> in $index (is gnuplot installed?)"; exit 1; }
[ "$csvs" -ge 1 ] || { echo "FAIL: no CSV link in $index"; exit 1; }
while IFS= read -r ref; do
  case "$ref" in
    *:*|/*) echo "FAIL: '$ref' is not a relative path inside the report"; exit 1 ;;
  esac
  decoded=$(printf '%b' "${ref//%/\\x}")
  [ -f "$out/report/$decoded" ] || { echo "FAIL: '$ref' in index.html names no file"; exit 1; }
done <<< "$refs"

if [ -z "$chromium" ]; then
  echo "SKIP: chromium not found (Debian: apt-get install chromium); links checked, rendering not"
  exit 77
fi
profile=$(mktemp -d)
trap 'rm -rf "$profile"' EXIT
shot="$out/report-screenshot.png"
timeout 180 "$chromium" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
  --disable-background-networking --disable-component-update --disable-sync --user-data-dir="$profile" \
  --screenshot="$shot" --window-size=1200,3000 "file://$(realpath "$index")" > "$out/chromium.log" 2>&1 \
  || { cat "$out/chromium.log"; echo "FAIL: chromium could not render the page"; exit 1; }
[ -s "$shot" ] || { cat "$out/chromium.log"; echo "FAIL: no screenshot"; exit 1; }

# Not one uniform colour, and enough contrast somewhere to be text and plots.
stats=$(oiiotool --stats "$shot")
echo "$stats"
echo "$stats" | grep -q '1200 x 3000' || { echo "FAIL: screenshot is not 1200 x 3000"; exit 1; }
echo "$stats" | grep -q 'Constant: No' || { echo "FAIL: the screenshot is one uniform colour"; exit 1; }
echo "$stats" | awk '/Stats StdDev:/ { for (i = 3; i <= 5; ++i) if ($i + 0 > best) best = $i + 0 }
                     END { exit !(best >= 15) }' \
  || { echo "FAIL: the screenshot is nearly blank (channel standard deviations below 15 of 255)"; exit 1; }
echo "PASS: report at $index, screenshot $shot"
