#!/usr/bin/env bash
# hapticctl's bash completion as bash runs it: the script hapticctl generates from its own
# command-line definition completes subcommands, their options, the global options, the
# method names and, for record and plot, file names.
# Usage: bash_completion_test.sh HAPTICCTL
set -euo pipefail
hapticctl=$1
script=$(mktemp)
trap 'rm -f "$script"' EXIT
"$hapticctl" --bash-completion >"$script"
bash -n "$script"

# The words bash would offer for a command line whose last word is being typed.
complete_words() {
  bash -c 'source "$1"; shift; COMP_WORDS=("$@"); COMP_CWORD=$(($# - 1)); _hapticctl
           printf "%s\n" "${COMPREPLY[@]}" | sort | tr "\n" " "' _ "$script" "$@"
}
expect() {
  local got want=$1; shift
  got=$(complete_words "$@")
  if [[ " $got " != *" $want "* ]]; then
    echo "FAIL: '$*' offers '$got', not '$want'" >&2; exit 1
  fi
}
refuse() {
  local got unwanted=$1; shift
  got=$(complete_words "$@")
  if [[ " $got " == *" $unwanted "* ]]; then
    echo "FAIL: '$*' offers '$unwanted' ($got)" >&2; exit 1
  fi
}

expect method hapticctl me
expect status hapticctl st
expect --over-dds hapticctl --ov
expect --json hapticctl status --j
expect --timeout hapticctl status --ti
expect linearized_subspace hapticctl method lin
expect anisotropic hapticctl --dds-domain 3 method an
expect --interval hapticctl watch --int
expect --duration hapticctl record --du
refuse --json hapticctl watch --j
refuse status hapticctl method s
refuse --version hapticctl status --ve
cd "$(dirname "$script")"
expect "$(basename "$script")" hapticctl plot "$(basename "$script" | cut -c1-4)"
echo "bash completion: every case offered as expected"
