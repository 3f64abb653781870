#!/usr/bin/env bash
# The man pages (man/selfsense.1, man/selfsensed.8) against the programs' --help, so that they
# cannot drift apart: every sub-command of `selfsense` (at every depth, from each --help's
# Subcommands list) has its own `.SS "selfsense PATH"` section and every section names a
# sub-command that exists; in each section, every option (--NAME) and positional argument of
# that sub-command's --help is listed (`.B`/`.BI \-\-NAME`, `.I NAME` in capitals), and nothing
# is listed that --help does not print. The same for selfsensed's options under `.SH OPTIONS`.
#
#   check_man.sh SELFSENSE SELFSENSED MAN_DIR
set -euo pipefail

tool=$1
daemon=$2
man_dir=$3
failures=0
fail() {
  echo "FAIL: $*"
  failures=$((failures + 1))
}

# From one --help text on stdin (CLI11's layout): "kind name" lines for its sub-commands,
# long options (without --help) and positionals.
help_items() {
  awk '
    /^[A-Za-z][A-Za-z ]*:$/ { section = $0; next }
    /^  [^ ]/ {
      if (section == "Subcommands:") print "sub " $1
      else if (section == "Positionals:") print "arg " toupper($1)
      else if (section == "Options:") {
        n = split($1, names, ",")
        for (i = 1; i <= n; i++)
          if (names[i] ~ /^--/ && names[i] != "--help") print "opt " substr(names[i], 3)
      }
    }'
}

# From a man page section on stdin: the options and positionals it lists, as help_items.
man_items() {
  sed -n -e 's/^\.BI\{0,1\} \\-\\-\([a-z0-9\\-]*\).*/opt \1/p' -e 's/^\.I \([A-Z][A-Z0-9_]*\)$/arg \1/p' |
    sed 's/\\-/-/g'
}

# The text of a section of a man page: from the line equal to HEADER to the next .SS or .SH.
man_section() {  # man_section FILE HEADER
  awk -v header="$2" '$0 == header { on = 1; next } on && /^\.S[SH] / { exit } on' "$1"
}

# compare WHAT HELP_ITEMS MAN_ITEMS: both ways.
compare() {
  local what=$1 item
  while read -r item; do
    [ -n "$item" ] || continue
    grep -qxF "$item" <<<"$3" || fail "$what: '${item#* }' (${item%% *}) is in --help, not in the man page"
  done <<<"$2"
  while read -r item; do
    [ -n "$item" ] || continue
    grep -qxF "$item" <<<"$2" || fail "$what: '${item#* }' (${item%% *}) is in the man page, not in --help"
  done <<<"$3"
}

page=$man_dir/selfsense.1
[ -f "$page" ] || { echo "FAIL: $page missing"; exit 1; }
commands=0
options=0
sections_seen=()
walk() {  # walk SUBCOMMAND...: one sub-command path, then its sub-commands
  local help items header sub
  help=$("$tool" "$@" --help) || { fail "selfsense $* --help failed"; return; }
  items=$(help_items <<<"$help")
  if [ $# -gt 0 ]; then
    commands=$((commands + 1))
    options=$((options + $(grep -c '^opt ' <<<"$items" || true)))
    header=".SS \"selfsense $*\""
    sections_seen+=("$header")
    if grep -qxF "$header" "$page"; then
      compare "selfsense $*" "$(grep -v '^sub ' <<<"$items" || true)" "$(man_section "$page" "$header" | man_items)"
    else
      fail "selfsense $*: no section $header in $(basename "$page")"
    fi
  fi
  while read -r _ sub; do
    walk "$@" "$sub"
  done < <(grep '^sub ' <<<"$items" || true)
}
walk
[ "$commands" -gt 10 ] || fail "selfsense --help listed only $commands sub-commands"
# Sections for sub-commands that no longer exist.
while read -r header; do
  printf '%s\n' "${sections_seen[@]}" | grep -qxF "$header" ||
    fail "$(basename "$page"): $header names no sub-command of selfsense"
done < <(grep '^\.SS "selfsense ' "$page")
echo "selfsense: $commands sub-commands and $options options in $(basename "$page")"

page=$man_dir/selfsensed.8
[ -f "$page" ] || { echo "FAIL: $page missing"; exit 1; }
help=$("$daemon" --help) || fail "selfsensed --help failed"
compare selfsensed "$(help_items <<<"$help")" "$(man_section "$page" '.SH OPTIONS' | man_items)"
echo "selfsensed: $(help_items <<<"$help" | grep -c '^opt ') options in $(basename "$page")"

# The pages themselves: man reads them without a warning.
if command -v man >/dev/null; then
  for page in "$man_dir/selfsense.1" "$man_dir/selfsensed.8"; do
    warnings=$(LC_ALL=C.UTF-8 MANWIDTH=80 man --warnings -l "$page" 2>&1 >/dev/null || true)
    [ -z "$warnings" ] || fail "$(basename "$page"): man --warnings: $warnings"
  done
fi

if [ "$failures" -ne 0 ]; then
  echo "$failures check(s) failed"
  exit 1
fi
echo "man pages: in step with --help"
