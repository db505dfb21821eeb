#!/usr/bin/env bash
# The resilience study again with issue 55's design: n = 10 runs per cell, run i of every
# system and level on perturbation draw i (paired), --mapping-lag 3 as before. Each block writes
# its own folder and resumes where it stopped (re-run the script); the tables at the end.
# NF=<noisefree binary> to use another build.
set -euo pipefail
cd "$(dirname "$0")/../.."
NF=${NF:-target/release/noisefree}
export NOISEFREE_SYNTH_CACHE=${NOISEFREE_SYNTH_CACHE:-target/synth-frames}
SYSTEMS=orb,mcor,avc,mcor+avc,rc
# 1. The real EuRoC frames (V1_01's first 95 stereo pairs) under occluders and the image
#    families.
"$NF" sweep --path ../shared/data/euroc_v101_head --configs "$SYSTEMS" --runs 10 --mapping-lag 3 \
  --perturb image-noise:0,4,8,16,32 --perturb motion-blur:0,2,4,8,16 --perturb exposure:0,10,20,40 \
  --perturb jpeg:0,90,50,20,5 --perturb occluders:0,1,2,4,8 --perturb stereo-misalignment:0,0.1,0.2,0.5,1 \
  --quiet --out results/resilience/euroc-real-n10
"$NF" table results/resilience/euroc-real-n10
# 2. fr2_coke's twin where depth noise does break it, and the cells left unrun before. The
#    cheap axes in one folder (its level-0 runs are block 3's, the same keys, copied in before
#    it ran). The axial cells in another: a run at depth-axial 512 or 1000 makes a keyframe of
#    nearly every frame (local BA over 230-340 keyframes, 2-5 min a run); its level-0 and 128 x
#    runs are block 3's too.
"$NF" sweep --seq twin_fr2_coke --frames 400 --configs "$SYSTEMS" --runs 10 --mapping-lag 3 \
  --perturb depth-scale:0,5,10,20 --perturb depth-lag:0,2,4,8 --perturb occluders:0,1,2,4,8 \
  --perturb depth-holes:0,50,80 --quiet --out results/resilience/coke-breaking-n10
"$NF" table results/resilience/coke-breaking-n10
"$NF" sweep --seq twin_fr2_coke --frames 400 --configs "$SYSTEMS" --runs 10 --mapping-lag 3 \
  --perturb depth-axial:0,128,512,1000 --quiet --out results/resilience/coke-axial-n10
"$NF" table results/resilience/coke-axial-n10
# 3. Three RGB-D twins under axial depth noise up to 128 x Nguyen's sigma.
"$NF" sweep --seq twin_fr2_coke,twin_fr1_desk,twin_fr3_office --frames 400 --configs "$SYSTEMS" \
  --runs 10 --mapping-lag 3 --perturb depth-axial:0,1,2,4,8,16,32,64,128 \
  --quiet --out results/resilience/twins-n10
"$NF" table --paper results/resilience/twins-n10
# 4. The real ORB-SLAM3 (the pip wheel, systems/orbslam3-pip.toml) beside ours on `kinect`,
#    n = 10 with paired draws (the n = 3 folder resilience/orbslam3 shared one draw).
"$NF" sweep --seq kinect --frames 300 --configs "$SYSTEMS",orbslam3pip --config systems/orbslam3-pip.toml \
  --runs 10 --mapping-lag 3 --perturb occluders:0,1,2,4 --perturb depth-axial:0,4,16,64 \
  --quiet --out results/resilience/orbslam3-n10
"$NF" table results/resilience/orbslam3-n10
# 5. The lateral axis of the same three twins (the n = 3 twins/ folder's other half). Its level-0
#    runs are block 3's (the same keys), copied into the folder before it ran.
"$NF" sweep --seq twin_fr2_coke,twin_fr1_desk,twin_fr3_office --frames 400 --configs "$SYSTEMS" \
  --runs 10 --mapping-lag 3 --perturb depth-lateral:0,1,2,4,8,16,32 \
  --quiet --out results/resilience/twins-lateral-n10
"$NF" table --paper results/resilience/twins-lateral-n10
