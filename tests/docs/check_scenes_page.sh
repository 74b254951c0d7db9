#!/usr/bin/env bash
# ctest docs_scenes: docs/scenes.md must be exactly what `knotflow --scene-reference` prints (the
# scene catalogue of src/scene), so that the page cannot drift from the code.
#   check_scenes_page.sh KNOTFLOW_EXE SOURCE_DIR
set -euo pipefail
exe="$1"
page="$2/docs/scenes.md"
generated="$(mktemp)"
trap 'rm -f "$generated"' EXIT
"$exe" --scene-reference >"$generated"
if ! diff -u "$page" "$generated"; then
  echo "docs/scenes.md differs from the scene catalogue (the diff above: - the page, + the code)." >&2
  echo "Regenerate it from the top of the repository with:" >&2
  echo "    build/bin/knotflow --scene-reference > docs/scenes.md" >&2
  exit 1
fi
echo "docs/scenes.md matches knotflow --scene-reference ($(wc -l <"$page") lines)"
