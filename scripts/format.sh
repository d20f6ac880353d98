#!/usr/bin/env bash
# Formats the C++ sources with .clang-format (clang-format 14, Debian 12's), or with --check lists
# the files that are not formatted and fails. Installs clang-format when missing.
# Usage: scripts/format.sh [--check]
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"
if ! command -v clang-format > /dev/null; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends clang-format > /dev/null
fi
# Tracked files and new ones not yet added (a new file is formatted before its first commit).
mapfile -t files < <(git ls-files --cached --others --exclude-standard '*.cpp' '*.hpp')
if [ "${1:-}" = "--check" ]; then
  bad=()
  for f in "${files[@]}"; do
    clang-format --dry-run --Werror "$f" > /dev/null 2>&1 || bad+=("$f")
  done
  if ((${#bad[@]})); then
    echo "not formatted (run scripts/format.sh): ${bad[*]}"
    exit 1
  fi
  echo "all ${#files[@]} C++ files formatted"
else
  clang-format -i "${files[@]}"
fi
