#!/usr/bin/env bash
# The import graph of every crate and of the CLI's src/, test code included: no circle between
# files or top-level modules anywhere, and the layers synth and ate-eval declare kept. Exits
# non-zero on the first failure, naming it (tools/import_graph.py prints the circle).
set -euo pipefail
cd "$(dirname "$0")/.."
status=0
for src in src crates/*/src; do
  if ! python3 tools/import_graph.py "$src" --quiet > /tmp/layers.$$ 2>&1; then
    echo "import circle in $src:"; grep -E 'CIRCLE|UP' /tmp/layers.$$ || cat /tmp/layers.$$
    status=1
  fi
done
rm -f /tmp/layers.$$
python3 tools/import_graph.py crates/synth/src --docs --quiet \
  --layers "error hash | world | motion | sensor | spec | generator | output | catalog" || status=1
python3 tools/import_graph.py crates/ate-eval/src --docs --quiet \
  --layers "error trajectory stats | associate align | stamps | io | ate | rpe" || status=1
[ "$status" = 0 ] && echo "layers: no circle in src/ or any crate; synth and ate-eval keep their layers"
exit "$status"
