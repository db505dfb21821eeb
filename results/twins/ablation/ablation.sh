#!/usr/bin/env bash
# Baseline ATE on a twin with each effect alone, none, and all (orb, seed 0, N frames).
set -u
SEQ=${1:-twin_fr1_desk}; N=${2:-300}; OUT=${3:-/tmp/ablation}
BIN=${NOISEFREE:-target/release/noisefree}
ALL="lens blur rolling_shutter vignetting auto_exposure sensor_noise tremor depth_lag axial quantisation lateral holes"
mkdir -p $OUT
run() { # name, without-list
  local name=$1 without=$2
  local args=()
  [ -n "$without" ] && args=(--synth-without "$without")
  $BIN run --seq $SEQ --frames $N --quiet --out $OUT/$name "${args[@]}" 2>&1 | tail -1 | sed "s/^/$name: /"
}
run all ""
run none "$(echo $ALL image_noise | tr ' ' ',')"
for x in $ALL; do
  others=$(for y in $ALL; do [ $y != $x ] && echo -n "$y,"; done)
  if [ $x = sensor_noise ]; then w=${others%,}; else w=${others}image_noise; fi
  run "only_$x" "$w"
done
