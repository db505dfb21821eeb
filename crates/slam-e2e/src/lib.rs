//! slam-e2e: the SLAM system of `slam-core` run end to end on sequences rendered by `synth`.
//! It holds no code of its own; it is where the tests and benches live that need rendered
//! frames, so that `slam-core`, the bottom of the workspace, depends on nothing of it (not
//! even for its own tests) and `synth` can use `slam-core` without a circle.
//!
//! - `tests/end_to_end.rs`: the ORB-SLAM2 baseline on the presets (accuracy, relocalization
//!   after an occlusion, bit-identical reruns, mapping lag); `tests/loop_closing.rs`: a
//!   revisit verified and a larger replica of the place refused, a loop closed under mapping
//!   lag; `tests/place_recognition.rs`: a kidnapped camera relocalized at once, BoW-guided
//!   against brute-force matching; `tests/common/mod.rs`: rendering a sequence, running the
//!   system, scoring it.
//! - `benches/system.rs`: whole-pipeline frames per second (`cargo bench -p slam-e2e --bench
//!   system`); `benches/relocalization.rs`: relocalization against 1000 keyframes;
//!   `benches/loop_closing.rs`: loop closing, essential graph and global BA on a real map.
//!
//! The benches of `slam-core` that need no rendered frames (ORB extraction, optimization,
//! place recognition) stay in `crates/slam-core/benches`.
