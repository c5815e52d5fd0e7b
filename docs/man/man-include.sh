#!/usr/bin/env bash
# man-include.sh EXECUTABLE STATIC.h2m: the help2man include file of EXECUTABLE, STATIC.h2m
# (its hand-written sections) followed, for a program with CLI11 subcommands, by a
# [SUBCOMMANDS] section holding each subcommand's own --help.
set -euo pipefail
executable="$1"
cat "$2"
subcommands=$("$executable" --help | awk '/^Subcommands:/ { on = 1; next } on && NF { print $1 }')
[[ -n "$subcommands" ]] || exit 0
echo "[SUBCOMMANDS]"
for subcommand in $subcommands; do
    echo ".SS $subcommand"
    echo ".nf"
    # Roff: a leading dot or quote would be a request; a backslash an escape.
    "$executable" "$subcommand" --help | sed -e 's/\\/\\e/g' -e "s/^\([.']\)/\\\\\&\1/"
    echo ".fi"
done
