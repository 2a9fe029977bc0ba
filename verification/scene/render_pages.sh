#!/usr/bin/env bash
# Opens the certification report and the benchmark dashboard in headless Chromium and checks
# that they render: the DOM Chromium built holds the expected tables and inline SVG plots with
# polylines, and a screenshot of each page is far from blank (its PNG is much larger than the
# PNG of an empty page of the same size — an empty page compresses to almost nothing).
# Usage: render_pages.sh INCISE SOURCE_DIR WORK_DIR. Exit 77 (ctest skip) without Chromium
# (install it with INCISE_WITH_CHROMIUM=1 ci/install-deps.sh).
set -euo pipefail
incise=$1 src=$2 work=$3
browser=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$browser" ]; then
  echo "render_pages: chromium not installed; skipping" >&2
  exit 77
fi
rm -rf "$work" && mkdir -p "$work"
chrome() { "$browser" --headless --no-sandbox --disable-gpu --window-size=1200,2400 "$@" 2>/dev/null; }

# The pages: quick certification report, and a dashboard from two stored synthetic runs.
(cd "$src" && "$incise" certify --quick --out "$work/certify" >/dev/null) || true
mkdir -p "$work/bench" && cp -r "$src/verification/scene/fixtures/runs" "$work/bench/"
"$incise" bench --dashboard-only --out "$work/bench" >/dev/null
echo '<!DOCTYPE html><html><body></body></html>' >"$work/blank.html"
chrome --screenshot="$work/blank.png" "file://$work/blank.html" >/dev/null
blank=$(stat -c %s "$work/blank.png")

fail=0
check_page() {  # page, min_svgs, required element id
  local page=$1 min_svgs=$2 id=$3
  local dom="$work/$(basename "$(dirname "$page")").dom.html"
  local png="$work/$(basename "$(dirname "$page")").png"
  chrome --dump-dom "file://$page" >"$dom"
  local svgs polylines
  svgs=$(grep -o '<svg class="incise-plot"' "$dom" | wc -l)
  polylines=$(grep -o '<polyline' "$dom" | wc -l)
  chrome --screenshot="$png" "file://$page" >/dev/null
  local size
  size=$(stat -c %s "$png")
  echo "render_pages: $page: $svgs plots, $polylines polylines, screenshot $size bytes (blank $blank)"
  if [ "$svgs" -lt "$min_svgs" ] || [ "$polylines" -lt "$min_svgs" ]; then
    echo "render_pages: FAIL: expected at least $min_svgs plots with polylines in $page" >&2
    fail=1
  fi
  if ! grep -q "id=\"$id\"" "$dom"; then
    echo "render_pages: FAIL: element #$id missing in $page" >&2
    fail=1
  fi
  # Non-blank: 10x the empty page (observed at 1200x2400: report ~470 kB, dashboard ~186 kB,
  # empty page ~13 kB).
  if [ "$size" -le $((10 * blank)) ]; then
    echo "render_pages: FAIL: screenshot of $page looks blank" >&2
    fail=1
  fi
}
check_page "$work/certify/index.html" 4 summary
# The dashboard of the two fixture runs: one time chart per benchmark (their MFLOP/s and tets/s
# are rates from time, written in the captions; docs/scenes.md "incise bench").
check_page "$work/bench/index.html" 2 comparison
exit $fail
