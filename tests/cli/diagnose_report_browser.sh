#!/usr/bin/env bash
# The diagnosis report in a real browser: headless Chromium opens it without console messages
# (the page's Content-Security-Policy forbids scripts and any resource from elsewhere, so a
# violation would be logged), parses every inline SVG, and draws the plots (pixels that are not
# white and pixels in the plot colours, below the tables). A page without plots, also loaded
# with a blocked resource, must fail the same checks, so they can fail.
# Usage: diagnose_report_browser.sh HELPER_BINARY. Fails (not skips) without chromium.
set -euo pipefail
helper=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
command -v chromium >/dev/null || fail "chromium is not installed (scripts/setup.sh installs it)"

browser() {
  # A profile of its own: no state shared with other runs; no D-Bus noise matters, only the
  # page's console lines (":CONSOLE") are checked.
  timeout 25 chromium --headless=new --no-sandbox --disable-gpu --no-first-run \
    --user-data-dir="$work/profile" --window-size=1200,3000 --hide-scrollbars \
    --enable-logging=stderr --v=0 "$@"
}

# ink PNG: "ink coloured rows_with_ink" of the rows below the tables (700..3000).
region() { "$helper" ink "$1" 700 3000 | sed 's/.* ink=\([0-9]*\) coloured=\([0-9]*\) rows_with_ink=\([0-9]*\)/\1 \2 \3/'; }

"$helper" write "$work/report.html" 100000
[ -s "$work/report.html" ] || fail "no report written"

browser --screenshot="$work/report.png" "file://$work/report.html" >/dev/null 2>"$work/shot.log" ||
  { tail -20 "$work/shot.log" >&2; fail "chromium could not take the screenshot"; }
[ -s "$work/report.png" ] || fail "no screenshot"
if grep -a ':CONSOLE' "$work/shot.log" >&2; then fail "the report logged console messages"; fi

browser --dump-dom "file://$work/report.html" >"$work/dom.html" 2>"$work/dom.log" ||
  { tail -20 "$work/dom.log" >&2; fail "chromium could not load the report"; }
if grep -a ':CONSOLE' "$work/dom.log" >&2; then fail "the report logged console messages"; fi
svg_file=$(grep -o '<svg' "$work/report.html" | wc -l)
svg_dom=$(grep -o '<svg' "$work/dom.html" | wc -l)
path_file=$(grep -o '<path' "$work/report.html" | wc -l)
path_dom=$(grep -o '<path' "$work/dom.html" | wc -l)
[ "$svg_file" -gt 0 ] || fail "the report has no plots"
[ "$svg_dom" -eq "$svg_file" ] || fail "the browser parsed $svg_dom of $svg_file <svg> elements"
[ "$path_dom" -eq "$path_file" ] || fail "the browser parsed $path_dom of $path_file <path> elements"
grep -q '&lt;script&gt;' "$work/dom.html" || fail "the escaped path is not text in the page"

# Control: the same page head without plots, loading an image the policy blocks.
sed -n '1,/<body>/p' "$work/report.html" >"$work/blank.html"
printf '<h1>no plots</h1><img src="https://example.invalid/x.png" alt="">\n</body></html>\n' >>"$work/blank.html"
browser --screenshot="$work/blank.png" "file://$work/blank.html" >/dev/null 2>"$work/blank.log" ||
  { tail -20 "$work/blank.log" >&2; fail "chromium could not take the control screenshot"; }
grep -aq ':CONSOLE' "$work/blank.log" || fail "the console check does not see a blocked resource"

read -r ink coloured rows < <(region "$work/report.png")
read -r blank_ink blank_coloured blank_rows < <(region "$work/blank.png")
echo "plot region 1200x2300: report ink=$ink coloured=$coloured rows=$rows;" \
  "control ink=$blank_ink coloured=$blank_coloured rows=$blank_rows"
check() {  # ink coloured rows: the plot region is drawn
  [ "$1" -gt 55000 ] && [ "$2" -gt 20000 ] && [ "$3" -gt 1150 ]
}
check "$ink" "$coloured" "$rows" || fail "the plot region of the report looks blank"
if check "$blank_ink" "$blank_coloured" "$blank_rows"; then fail "a page without plots passes the check"; fi
echo "browser: report renders in $(chromium --version 2>/dev/null | head -n 1)"
