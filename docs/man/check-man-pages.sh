#!/usr/bin/env bash
# check-man-pages.sh MAN_DIR EXECUTABLE...: every option and subcommand each executable's
# --help lists is in its man page, and the page renders with man(1) without warnings.
set -euo pipefail
dir="$1"; shift
status=0
for executable in "$@"; do
    name=$(basename "$executable")
    page="$dir/$name.1"
    [[ -s "$page" ]] || { echo "$name: no man page at $page" >&2; status=1; continue; }
    rendered=$(MANWIDTH=200 man --warnings -l "$page" 2> "$dir/$name.warnings" | col -b)
    if [[ -s "$dir/$name.warnings" ]]; then
        echo "$name.1: man reports:" >&2; cat "$dir/$name.warnings" >&2; status=1
    fi
    for option in $("$executable" --help | grep -oE -- '--[a-z][a-z-]+' | sort -u); do
        grep -qF -- "$option" <<< "$rendered" || { echo "$name.1 lacks $option" >&2; status=1; }
    done
    for subcommand in $("$executable" --help | awk '/^Subcommands:/ { on = 1; next } on && NF { print $1 }'); do
        grep -qE "^ +$subcommand\$" <<< "$rendered" ||
            { echo "$name.1 lacks the subcommand section '$subcommand'" >&2; status=1; }
        for option in $("$executable" "$subcommand" --help | grep -oE -- '--[a-z][a-z-]+' | sort -u); do
            grep -qF -- "$option" <<< "$rendered" || { echo "$name.1 lacks $subcommand $option" >&2; status=1; }
        done
    done
done
[[ $status -eq 0 ]] && echo "man pages: $# pages match their command lines"
exit $status
