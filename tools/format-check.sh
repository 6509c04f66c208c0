#!/usr/bin/env bash
# Fails when clang-format would change any C++ file of the project.
#
#   tools/format-check.sh [CLANG_FORMAT]     (default: clang-format)
#
# Checks every *.h and *.cc under core/ platform/ daemon/ tools/ tests/: the files git
# tracks (plus untracked, not ignored ones) inside a git work tree, else all files found.
# Prints each file that differs and exits 1; exits 2 when clang-format cannot be run.
# The style is .clang-format at the top of the tree. Fix with `clang-format -i FILE`.
set -euo pipefail

clang_format="${1:-clang-format}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

if ! command -v "$clang_format" >/dev/null 2>&1; then
  echo "format-check: '$clang_format' not found" >&2
  exit 2
fi

dirs=(core platform daemon tools tests)
files=()
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  while IFS= read -r -d '' f; do
    [[ -f "$f" ]] && files+=("$f")
  done < <(git ls-files -z --cached --others --exclude-standard -- \
             "${dirs[@]/%//*.h}" "${dirs[@]/%//*.cc}" | sort -zu)
else
  existing=()
  for d in "${dirs[@]}"; do [[ -d "$d" ]] && existing+=("$d"); done
  if ((${#existing[@]})); then
    while IFS= read -r -d '' f; do
      files+=("$f")
    done < <(find "${existing[@]}" -type f \( -name '*.h' -o -name '*.cc' \) -print0 | sort -z)
  fi
fi

if ((${#files[@]} == 0)); then
  echo "format-check: no C++ files found"
  exit 0
fi

bad=()
for f in "${files[@]}"; do
  if ! "$clang_format" --style=file --dry-run --Werror "$f" >/dev/null 2>&1; then
    bad+=("$f")
  fi
done

if ((${#bad[@]})); then
  echo "format-check: ${#bad[@]} of ${#files[@]} files need clang-format:" >&2
  printf '  %s\n' "${bad[@]}" >&2
  echo "fix with: $clang_format -i <file>..." >&2
  exit 1
fi
echo "format-check: ${#files[@]} files clean"
