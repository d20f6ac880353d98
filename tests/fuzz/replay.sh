#!/usr/bin/env bash
# Replays the regression corpus: regressions/<reader>/<file>, each read in place of that reader's
# seed input; any crash, hang or internal error fails.
set -euo pipefail
FUZZ=$1
DIR=$2
status=0
found=0
for reader_dir in "$DIR"/*/; do
  [ -d "$reader_dir" ] || continue
  files=("$reader_dir"*)
  [ -e "${files[0]}" ] || continue
  found=1
  "$FUZZ" --replay "$(basename "$reader_dir")" "${files[@]}" || status=1
done
[ $found = 1 ] || echo "no regression inputs yet"
exit $status
