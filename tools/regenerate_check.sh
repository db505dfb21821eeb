#!/usr/bin/env bash
# Every committed table and figure regenerates byte for byte: each folder of results/ with a
# runs.csv is copied, its tables made again by `noisefree table` (with --paper where its table3.md has the
# paper's column) and compared with the committed files: Markdown, CSV, folder indexes and the
# figures (PNG and SVG, drawn by the pinned plotting crate with the embedded font).
# Usage: tools/regenerate_check.sh [NOISEFREE_BINARY] [FOLDER...]
set -euo pipefail
cd "$(dirname "$0")/.."
NF=${1:-target/release/noisefree}
shift || true
folders=("$@")
if [ ${#folders[@]} -eq 0 ]; then
  mapfile -t folders < <(find results -name runs.csv -printf '%h\n' | sort)
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
status=0
for d in "${folders[@]}"; do
  [ -f "$d/tables.md" ] || [ -f "$d/table3.md" ] || continue
  copy="$tmp/$d"
  mkdir -p "$(dirname "$copy")"
  cp -r "$d" "$copy"
  paper=()
  grep -q "(paper)" "$d/table3.md" 2>/dev/null && paper=(--paper)
  if ! "$NF" table "${paper[@]}" "$copy" > "$tmp/out.txt" 2>&1; then
    echo "FAIL $d: noisefree table failed"; cat "$tmp/out.txt"; status=1; continue
  fi
  for f in "$d"/*.md "$d"/*.csv "$d"/figures/*.png "$d"/figures/*.svg; do
    [ -f "$f" ] || continue
    case "$(basename "$f")" in runs.csv|planned.csv|frames.csv) continue ;; esac
    rel=${f#"$d"/}
    if ! cmp -s "$f" "$copy/$rel"; then
      # The first line of a tables.md names the folder as it was given.
      if [ "$rel" = tables.md ] && \
        diff <(tail -n +2 "$f") <(tail -n +2 "$copy/tables.md") > /dev/null; then
        continue
      fi
      echo "DIFFERS $f"; status=1
      case "$f" in *.md|*.csv) diff "$f" "$copy/$rel" | head -6 ;; esac
    fi
  done
done
[ "$status" = 0 ] && echo "regenerate: every committed table and figure of ${#folders[@]} folders made again, byte for byte"
exit "$status"
