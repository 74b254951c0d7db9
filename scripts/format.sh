#!/usr/bin/env bash
# The one layout of the Fortran sources: every statement of src/ and tests/ (*.f90, *.F90)
# indented by findent with the flags in .findent (2 spaces a level; continuation lines, comments
# in column 1 and preprocessor lines as written). findent changes only leading blanks: it never
# splits, joins or reflows a line, so no line gets longer than its contents and indentation.
# This script checks that too: a file whose formatted text differs in anything but leading blanks
# is an error and is left as it was.
#
#   bash scripts/format.sh           rewrite the files that differ (idempotent; about a second)
#   bash scripts/format.sh --check   list the files that differ and exit 1 if any
#                                    (ctest format_check); exit 77 when findent is missing
#
# Not formatted: the pFUnit .pf files (their @ directives are not Fortran) and the fypp template
# src/io/kf_h5.fypp (findent does not parse its generated ${...}$ names; laid out by hand in the
# same style). findent: $KNOTFLOW_FINDENT, else findent on PATH, else build/venv/bin/findent
# (scripts/build.sh and scripts/test.sh install it there with the tools' [fortran] extra).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

check=0
case "${1:-}" in
  "") ;;
  --check) check=1 ;;
  *) printf 'usage: bash scripts/format.sh [--check]\n' >&2; exit 2 ;;
esac

findent="${KNOTFLOW_FINDENT:-}"
if [ -z "$findent" ]; then
  if command -v findent >/dev/null 2>&1; then
    findent="$(command -v findent)"
  elif [ -x "$root/build/venv/bin/findent" ]; then
    findent="$root/build/venv/bin/findent"
  fi
fi
if [ -z "$findent" ] || [ ! -x "$findent" ]; then
  printf 'SKIP: findent not found (bash scripts/build.sh installs it into build/venv; or pip install findent)\n'
  [ "$check" = 1 ] && exit 77
  exit 1
fi

flags=()
while read -r line; do
  line="${line%%#*}"
  for word in $line; do flags+=("$word"); done
done <"$root/.findent"

tmp="$(mktemp)"
trap 'rm -f "$tmp"' EXIT
differ=()
while IFS= read -r f; do
  "$findent" "${flags[@]}" <"$f" >"$tmp"
  cmp -s "$f" "$tmp" && continue
  # Only leading blanks may change.
  if ! cmp -s <(sed 's/^[[:space:]]*//' "$f") <(sed 's/^[[:space:]]*//' "$tmp"); then
    printf 'ERROR: findent would change more than the indentation of %s; left as it is\n' "$f" >&2
    exit 1
  fi
  differ+=("$f")
  [ "$check" = 0 ] && cat "$tmp" >"$f"
done < <(find src tests -type f \( -name '*.f90' -o -name '*.F90' \) | LC_ALL=C sort)

if [ "$check" = 1 ]; then
  if [ "${#differ[@]}" -gt 0 ]; then
    printf 'not in the layout of scripts/format.sh (run it to fix):\n'
    printf '  %s\n' "${differ[@]}"
    exit 1
  fi
  printf 'format_check: every Fortran source is in the layout of scripts/format.sh\n'
else
  printf 'format.sh: %d file(s) reformatted\n' "${#differ[@]}"
fi
