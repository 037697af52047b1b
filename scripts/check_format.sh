#!/usr/bin/env bash
# Checks that every tracked C++ file is formatted as .clang-format says (Debian's clang-format).
# Fix with: scripts/check_format.sh --fix
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
if ! command -v clang-format >/dev/null 2>&1; then  # scripts/setup.sh installs it
  echo "[format] clang-format is missing: run scripts/setup.sh (or apt-get install clang-format)" >&2
  exit 1
fi
mapfile -t files < <(git ls-files '*.cpp' '*.h')
if [[ "${1:-}" == "--fix" ]]; then
  clang-format --style=file -i "${files[@]}"
  echo "[format] formatted ${#files[@]} files"
  exit 0
fi
if ! clang-format --style=file --dry-run --Werror "${files[@]}" 2>/tmp/check_format.log; then
  grep -E "^[^ ].*: (error|warning):" /tmp/check_format.log | cut -d: -f1 | sort -u | sed 's/^/[format] not formatted: /'
  echo "[format] $(clang-format --version): run scripts/check_format.sh --fix"
  exit 1
fi
echo "[format] ${#files[@]} files formatted as .clang-format says"
