#!/usr/bin/env bash
# The readings study (issue 72): every reading of what the paper leaves unsaid, as a column
# beside the baseline and today's techniques, n = 10 paired runs, full length, --mapping-lag 3
# as results/table3-twins. Each block writes its own folder and resumes where it stopped
# (re-run the script); the tables at the end. NF=<noisefree binary> to use another build.
#
# Readings (slam-core `McorParams` / `AvcParams`, results/README.md "readings/"):
#   mcor:sightings=all          outlier sightings stay in the cluster (paper II, "Lack of Consensus")
#   mcor:verdict=consensus      MC-OR's pass keeps a match the chi2 test would drop (paper II)
#   mcor:scope=tracking+mapping MC-OR's verdicts gate local BA and cull points (Table IV)
#   mcor:paper                  the three together: the paper's stated mechanisms
#   avc:gate=3dof               AVC's residual gated at ORB-SLAM2's stereo 7.815
#   avc:b_role=camera           b is the RGB-D camera's baseline, close/far threshold included
set -euo pipefail
cd "$(dirname "$0")/../.."
NF=${NF:-target/release/noisefree}
export NOISEFREE_SYNTH_CACHE=${NOISEFREE_SYNTH_CACHE:-target/synth-frames}
# 1. Screening: every reading alone and the paper's mechanisms together, on the rows where the
#    paper's gains are largest and its headline. Seeds 0..9: the draws of table3-twins, which
#    chose no reading; a comparison that follows from this screening runs on fresh seeds.
COLUMNS=orb,mcor,avc,mcor+avc
COLUMNS+=,mcor:sightings=all,mcor:verdict=consensus,mcor:scope=tracking+mapping,mcor:paper
COLUMNS+=,avc:gate=3dof,avc:b_role=camera,mcor+avc:paper:gate=3dof:b_role=camera
ROWS=twin_fr3_w_static,twin_fr2_coke,twin_fr3_w_rpy,twin_fr3_w_xyz,twin_fr3_w_half
ROWS+=,twin_fr1_desk,twin_fr1_360,twin_fr1_room,twin_fr3_nst,twin_mh04,twin_v203
"$NF" sweep --seq "$ROWS" --configs "$COLUMNS" --runs 10 --mapping-lag 3 --quiet \
  --out results/readings/screening
"$NF" table --paper results/readings/screening
