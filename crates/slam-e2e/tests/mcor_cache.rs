//! MC-OR's cluster cache (slam_core::module::mcor_clusters) against the map it caches: a
//! system tracking people walking through the room, with keyframes, local mapping, culling and
//! fusion moving the map under it, checks every kept cluster a gate uses against one rebuilt
//! from the map, and every verdict kept across a frame's gates against one computed at the
//! gate's pose (`System::check_mcor_clusters`): a missed invalidation, a frame view taken
//! differently from a rebuild or a verdict kept beyond its reach panics.

mod common;

use common::render;
use slam_core::module::noise::{ClusterViews, McorParams};
use slam_core::system::{Config, System};
use synth::Preset;

#[test]
fn every_kept_cluster_is_the_cluster_the_map_gives() {
    let rendered = render(Preset::Walking.config(), 1, 90);
    for (views, lag) in [
        (ClusterViews::EveryFrame, 0),
        (ClusterViews::EveryFrame, 3),
        (ClusterViews::Keyframes, 2),
    ] {
        let config = Config {
            mcor: Some(McorParams {
                cluster_views: views,
                ..McorParams::default()
            }),
            mapping_lag: lag,
            ..Config::default()
        };
        let mut system = System::new(rendered.camera.clone(), config);
        system.check_mcor_clusters();
        let mut rejected = 0;
        for f in &rendered.frames {
            let r = system.track(f);
            rejected += r.stats.n_mcor_rejected_clusters + r.stats.n_mcor_rejected_features;
        }
        let (checked, verdicts) = system.check_mcor_clusters();
        // Dozens of keyframes (each one invalidates), thousands of clusters kept across frames
        // and checked, thousands of verdicts kept across rounds and checked, and a gate that
        // rejects.
        assert!(system.keyframe_count() >= 10, "{views:?} lag {lag}");
        assert!(checked > 5_000, "{views:?} lag {lag}: {checked} checked");
        assert!(
            verdicts > 5_000,
            "{views:?} lag {lag}: {verdicts} verdicts checked"
        );
        assert!(rejected > 0, "{views:?} lag {lag}");
    }
}
