#!/usr/bin/env bash
# Baseline (orb) ATE on a twin with every effect, with none, and with each effect alone:
# one sweep folder per variant (n runs, --mapping-lag 3, the twin's first FRAMES frames; each
# folder pins what it was rendered without), then SEQ.md / SEQ.csv assembled from the folders'
# Table III.
#   results/twins/ablation/ablation.sh [SEQ] [RUNS] [FRAMES] [OUT]
# "none" is the twin with every listed effect off: a pinhole camera in the fixed office,
# exact ground truth, noise-free images and depth; "only_X" adds X alone to "none".
# RERUN="all only_X ..." sweeps just those variants afresh (their folders replaced) and keeps
# the other variants' folders as they are (for an effect added later: the other variants'
# configurations do not change), then assembles the table from every folder.
set -euo pipefail
SEQ=${1:-twin_fr1_desk}
RUNS=${2:-10}
FRAMES=${3:-300}
OUT=${4:-results/twins/ablation}
BIN=${NOISEFREE:-target/release/noisefree}
# The effects to ablate (override with EFFECTS="..." for a twin that has fewer, e.g. EuRoC's).
ALL=${EFFECTS:-"lens blur rolling_shutter vignetting auto_exposure sensor_noise tremor depth_lag \
axial quantisation lateral holes mocap_noise layout stamp_jitter mocap_clock"}
mkdir -p "$OUT"

sweep() { # name, comma-separated effects to switch off (may be empty)
  local dir="$OUT/$SEQ/$1"
  if [ -n "${RERUN:-}" ]; then
    case " $RERUN " in
      *" $1 "*) rm -rf "$dir" ;;
      *) return 0 ;;
    esac
  fi
  local args=(--seq "$SEQ" --configs orb --runs "$RUNS" --frames "$FRAMES" --mapping-lag 3 --jobs 1 --quiet --out "$dir")
  [ -n "$2" ] && args+=(--synth-without "$2")
  "$BIN" sweep "${args[@]}" >/dev/null
  "$BIN" table "$dir" >/dev/null 2>&1
  # runs.csv holds every figure of the table; the trajectories (MBs a variant) are not kept.
  rm -rf "$dir/trajectories" "$dir/figures"
}

all_but() { # the effects except $1, plus the constant image noise unless $1 is sensor noise
  local w=""
  for y in $ALL; do [ "$y" != "$1" ] && w="$w$y,"; done
  if [ "$1" = sensor_noise ]; then echo "${w%,}"; else echo "${w}image_noise"; fi
}

variants="all none"
sweep all ""
sweep none "$(all_but '')"
for x in $ALL; do
  sweep "only_$x" "$(all_but "$x")"
  variants="$variants only_$x"
done

# The ORB-SLAM2 cell of each folder's Table III (mean ± std over the runs, failures marked).
{
  echo "variant,effects on,ATE RMSE (m)"
  for v in $variants; do
    cell=$(awk -F, 'NR == 2 { print $3 }' "$OUT/$SEQ/$v/table3.csv")
    case $v in
      all) on="every effect" ;;
      none) on="none" ;;
      *) on="${v#only_}" ;;
    esac
    echo "$v,$on,$cell"
  done
} > "$OUT/$SEQ.csv.tmp" && mv "$OUT/$SEQ.csv.tmp" "$OUT/$SEQ.csv"
{
  echo "## Ablation on $SEQ (first $FRAMES frames): ORB-SLAM2 baseline, $RUNS runs per variant (--mapping-lag 3)"
  echo
  echo "| variant | effects on | ATE RMSE (m) |"
  echo "|---|---|---|"
  tail -n +2 "$OUT/$SEQ.csv" | awk -F, '{ printf "| %s | %s | %s |\n", $1, $2, $3 }'
  echo
  echo "Mean ± population std over seeds 0..$((RUNS - 1)); each variant is its own sweep folder"
  echo "under $SEQ/ (its sweep-settings.toml names the effects it was rendered without)."
} > "$OUT/$SEQ.md.tmp" && mv "$OUT/$SEQ.md.tmp" "$OUT/$SEQ.md"
echo "wrote $OUT/$SEQ.md"
