#!/usr/bin/env bash
# Fails, listing the files, when a tracked C++ source does not follow .clang-format.
# `bash scripts/check-format.sh --fix` formats them in place instead.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
# The style is that of Debian bookworm's clang-format (14); other versions break lines
# differently, so a newer local binary would report files that CI accepts.
formatter="${CLANG_FORMAT:-clang-format}"
if ! command -v "$formatter" >/dev/null; then
  echo "check-format: $formatter not found (bash scripts/setup-deps.sh installs it)" >&2
  exit 2
fi
mapfile -t sources < <(git ls-files -- '*.cpp' '*.hpp' '*.h' '*.cc')
if [ "${1:-}" = "--fix" ]; then
  printf '%s\0' "${sources[@]}" | xargs -0 -n 50 "$formatter" -i
  exit 0
fi
unformatted=()
for f in "${sources[@]}"; do
  if ! "$formatter" "$f" | cmp -s - "$f"; then unformatted+=("$f"); fi
done
if [ ${#unformatted[@]} -ne 0 ]; then
  echo "check-format: ${#unformatted[@]} of ${#sources[@]} files do not follow .clang-format:" >&2
  printf '  %s\n' "${unformatted[@]}" >&2
  echo "check-format: run 'bash scripts/check-format.sh --fix'" >&2
  exit 1
fi
echo "check-format: all ${#sources[@]} files follow .clang-format"
