//! slam-e2e: the SLAM system of `slam-core` run end to end on sequences rendered by `synth`.
//! It holds no code of its own; it is where the tests and benches live that need rendered
//! frames, so that `slam-core`, the bottom of the workspace, depends on nothing of it (not
//! even for its own tests) and `synth` can use `slam-core` without a circle.
//!
//! - `tests/integration/` (one test binary, a module per topic): `end_to_end` runs the
//!   ORB-SLAM2 baseline on the presets (accuracy, relocalization after an occlusion,
//!   bit-identical reruns, mapping lag); `loop_closing` verifies a revisit and refuses a larger
//!   replica of the place, and closes a loop under mapping lag; `place_recognition` relocalizes
//!   a kidnapped camera at once and checks BoW-guided against brute-force matching;
//!   `mcor_cache` checks MC-OR's cluster cache against the map; `common` renders a sequence
//!   (through the shared frame cache), runs the system and scores it.
//! - `benches/system.rs`: whole-pipeline frames per second (`cargo bench -p slam-e2e --bench
//!   system`); `benches/relocalization.rs`: relocalization against 1000 keyframes;
//!   `benches/loop_closing.rs`: loop closing, essential graph and global BA on a real map.
//!
//! The benches of `slam-core` that need no rendered frames (ORB extraction, optimization,
//! place recognition) stay in `crates/slam-core/benches`.
