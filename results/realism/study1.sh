#!/usr/bin/env bash
# Study 1 of issue 54: the twins under their camera's chain at the literature's levels, nothing
# tuned. For each twin, an ablation of its chain (the chain, each member alone, the chain
# without each member) with our baseline, 10 runs per point, run i of every point on
# perturbation draw i; then our baseline beside the real ORB-SLAM3 (pip wheel) and the real
# ORB-SLAM2 (systems/orbslam.toml: edit its program paths to your build) at chain levels 0 and 1. Frames are rendered once into the frame cache and shared by every sweep.
set -euo pipefail
cd "$(dirname "$0")/../.."
NF=${NF:-target/release/noisefree}
FRAMES=${FRAMES:-400}
export NOISEFREE_SYNTH_CACHE=${NOISEFREE_SYNTH_CACHE:-target/synth-frames}
for pair in "twin_fr1_desk kinect-fr1" "twin_fr2_desk kinect-fr2" "twin_fr3_office kinect-fr3"; do
  set -- $pair
  "$NF" sweep --seq "$1" --frames "$FRAMES" --configs orb --runs 10 --ablate "$2:1" \
    --perturb-per-run --quiet --out results/realism/ablation
done
"$NF" table --paper results/realism/ablation
for pair in "twin_fr1_desk kinect-fr1" "twin_fr2_desk kinect-fr2" "twin_fr3_office kinect-fr3"; do
  set -- $pair
  "$NF" sweep --seq "$1" --frames "$FRAMES" --configs orb,orbslam3pip \
    --config systems/orbslam3-pip.toml --runs 10 --perturb "$2:0,1" --perturb-per-run \
    --quiet --out results/realism/beside
done
for pair in "twin_fr1_desk kinect-fr1" "twin_fr2_desk kinect-fr2" "twin_fr3_office kinect-fr3"; do
  set -- $pair
  "$NF" sweep --seq "$1" --frames "$FRAMES" --configs orbslam2 --config systems/orbslam.toml \
    --runs 10 --perturb "$2:0,1" --perturb-per-run --quiet --out results/realism/beside
done
"$NF" table --paper results/realism/beside
