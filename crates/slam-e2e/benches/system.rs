//! Whole-pipeline throughput: frames per second of `System::track` over a synthetic 640x480
//! RGB-D sequence (`kinect` preset, rendered once up front), with the time split per stage
//! (features / tracking / local mapping / BA) printed from the per-frame statistics.
//!
//! Run: `cargo bench -p slam-e2e --bench system`.

use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion};
use slam_core::system::{Config, System};
use slam_core::FrameInput;
use synth::Preset;

const FRAMES: usize = 120;

fn inputs(preset: Preset) -> (slam_core::Camera, Vec<FrameInput>) {
    let gen = synth::Generator::new(preset.config(), 1);
    let frames = (0..FRAMES).map(|i| gen.frame(i).into_input()).collect();
    (gen.camera(), frames)
}

fn run(camera: &slam_core::Camera, frames: &[FrameInput], config: &Config) -> System {
    let mut system = System::new(camera.clone(), config.clone());
    for f in frames {
        system.track(f);
    }
    system
}

fn report(name: &str, camera: &slam_core::Camera, frames: &[FrameInput], config: &Config) {
    let t = Instant::now();
    let system = run(camera, frames, config);
    let wall = t.elapsed().as_secs_f64();
    let s = system.frame_stats();
    let sum = |f: fn(&slam_core::system::FrameStats) -> f64| {
        s.iter().map(f).sum::<f64>() / s.len() as f64
    };
    println!(
        "{name}: {:.1} frames/s over {} frames | per frame: features {:.2} ms, tracking {:.2} ms, \
         local mapping {:.2} ms, BA {:.2} ms | {} keyframes",
        frames.len() as f64 / wall,
        frames.len(),
        sum(|x| x.time_features_ms),
        sum(|x| x.time_tracking_ms),
        sum(|x| x.time_mapping_ms),
        sum(|x| x.time_ba_ms),
        system.keyframe_count()
    );
}

fn bench(c: &mut Criterion) {
    let (cam, frames) = inputs(Preset::Kinect);
    let config = Config::default();
    report("rgbd kinect", &cam, &frames, &config);
    let (scam, sframes) = inputs(Preset::Stereo);
    report("stereo", &scam, &sframes, &Config::stereo());
    let mut g = c.benchmark_group("system");
    g.sample_size(10);
    g.bench_function("track_120_rgbd_frames", |b| {
        b.iter(|| run(&cam, &frames, &config))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
