#!/usr/bin/env bash
# Checks the generated man pages and bash completion against the programs themselves: every
# subcommand of `calstand --help` (and of each subcommand with its own) has its section in
# calstand(1), every option of calstandd --help is in calstandd(8), both pages render without
# a groff warning, and the completion completes subcommands, nested subcommands and options.
#   check_cli_docs.sh MAN_DIR COMPLETION_DIR CALSTAND CALSTANDD
set -euo pipefail
man_dir="$1"; completion_dir="$2"; calstand="$3"; calstandd="$4"
failures=0
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }

subcommands() { "$@" --help | awk '/^Subcommands:/{s=1; next} s && /^  [^ ]/{print $1} s && /^$/{s=0}'; }
# calstand --help lists its subcommands under task headings (cli/src/help_layout.cpp): any
# unindented "Heading:" but Options and the footer's Example.
top_subcommands() {
  "$@" --help | awk '/^(Options|Positionals|Examples?):$/{s=0; next} /^[^ ].*:$/{s=1; next}
                     s && /^  [^ ]/{print $1} s && /^$/{s=0}'
}
options() { "$@" --help | awk '/^Options:/{s=1; next} s && /^  -/{print $1} s && /^$/{s=0}' | tr ',' '\n'; }

page="$(zcat "$man_dir/calstand.1.gz")"
top=($(top_subcommands "$calstand"))
[ ${#top[@]} -ge 10 ] || fail "calstand --help lists only ${#top[@]} subcommands"
for s in "${top[@]}"; do
  grep -qx ".SS calstand $(printf '%s' "$s" | sed 's/-/\\\\-/g')" <<< "$page" || fail "calstand.1 has no section for '$s'"
  for n in $(subcommands "$calstand" "$s"); do
    grep -qx ".SS calstand $(printf '%s %s' "$s" "$n" | sed 's/-/\\\\-/g')" <<< "$page" ||
      fail "calstand.1 has no section for '$s $n'"
  done
done
dpage="$(zcat "$man_dir/calstandd.8.gz")"
for o in $(options "$calstandd"); do
  grep '^\.B ' <<< "$dpage" | grep -qF -- "$(printf '%s' "$o" | sed 's/-/\\-/g')" ||
    fail "calstandd.8 lacks $o"
done
for p in calstand.1.gz calstandd.8.gz; do
  warnings="$(zcat "$man_dir/$p" | groff -man -Tutf8 -ww -z 2>&1 || true)"
  [ -z "$warnings" ] || fail "$p: groff says: $warnings"
done

complete_words() {  # PROGRAM WORDS...: what the completion offers for the last word
  local prog="$1"; shift
  bash -c 'source "$1"; shift; COMP_WORDS=("$@"); COMP_CWORD=$(($# - 1)); _$(echo "${COMP_WORDS[0]}" | tr -c "A-Za-z0-9_\n" _); printf "%s\n" "${COMPREPLY[@]}"' \
    _ "$completion_dir/$prog" "$prog" "$@"
}
offered="$(complete_words calstand "")"
for s in "${top[@]}"; do grep -qx -- "$s" <<< "$offered" || fail "completion of 'calstand ' lacks $s"; done
nested="$(subcommands "$calstand" device)"
[ -n "$nested" ] || fail "calstand device --help lists no subcommands"
offered="$(complete_words calstand device "")"
for n in $nested; do grep -qx -- "$n" <<< "$offered" || fail "completion of 'calstand device ' lacks $n"; done
offered="$(complete_words calstand run --)"
for o in $(options "$calstand" run | grep '^--'); do
  grep -qx -- "$o" <<< "$offered" || fail "completion of 'calstand run --' lacks $o"
done
[ "$(complete_words calstand run --st)" = "--station" ] || fail "'calstand run --st' does not complete to --station"
[ "$(complete_words calstandd --rec)" = "--recovery" ] || fail "'calstandd --rec' does not complete to --recovery"

if [ "$failures" -ne 0 ]; then echo "$failures failure(s)" >&2; exit 1; fi
echo "man pages and completion agree with ${#top[@]} subcommands of calstand and calstandd's options"
