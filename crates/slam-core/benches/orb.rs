//! ORB front-end benchmarks: whole extraction on a 640x480 frame, each stage alone (pyramid,
//! FAST, distribution, orientation, blur, descriptors), and stereo frame construction on a
//! 752x480 pair. Single thread. Run with `cargo bench -p slam-core --bench orb`.

use std::hint::black_box;
use std::sync::Arc;

use criterion::{criterion_group, criterion_main, Criterion};
use slam_core::feature::brief::{compute_descriptor, gaussian_blur};
use slam_core::feature::distribute::{distribute, QuadScratch};
use slam_core::feature::extractor::detect_level;
use slam_core::feature::fast::{Corner, FastScratch};
use slam_core::feature::orientation::{ic_angle, CirclePatch};
use slam_core::feature::test_scene::{test_frame, TestScene};
use slam_core::feature::{OrbConfig, OrbExtractor, Pyramid, EDGE_THRESHOLD};
use slam_core::frame::Frame;
use slam_core::{Camera, FrameInput, GrayImage};

fn stages(c: &mut Criterion) {
    let img = test_frame(1);
    let cfg = OrbConfig::default();
    let mut ex = OrbExtractor::new(cfg.clone());
    c.bench_function("orb/extract_640x480", |b| {
        b.iter(|| ex.extract(black_box(&img)))
    });

    let scale = ex.scale_info().clone();
    let mut pyr = Pyramid::new();
    c.bench_function("orb/stage/pyramid", |b| {
        b.iter(|| pyr.build(black_box(&img), &scale))
    });
    pyr.build(&img, &scale);

    let mut fast = FastScratch::default();
    let mut counts = Vec::new();
    let mut corners: Vec<Vec<Corner>> = vec![Vec::new(); scale.n_levels];
    c.bench_function("orb/stage/fast", |b| {
        b.iter(|| {
            for (l, out) in corners.iter_mut().enumerate() {
                out.clear();
                detect_level(&pyr.levels[l], 20, 7, &mut fast, &mut counts, out);
            }
        })
    });
    let n_corners: usize = corners.iter().map(|c| c.len()).sum();
    eprintln!("FAST corners over all levels: {n_corners}");

    let per_level = cfg.features_per_level();
    let mut quad = QuadScratch::default();
    let mut kept: Vec<Vec<usize>> = vec![Vec::new(); scale.n_levels];
    let bounds = |l: &GrayImage| {
        let e = (EDGE_THRESHOLD - 3) as f32;
        (e, e, l.width as f32 - e, l.height as f32 - e)
    };
    c.bench_function("orb/stage/distribute", |b| {
        b.iter(|| {
            for l in 0..scale.n_levels {
                let bx = bounds(&pyr.levels[l]);
                distribute(&corners[l], bx, per_level[l], &mut quad, &mut kept[l]);
            }
        })
    });

    let patch = CirclePatch::default();
    c.bench_function("orb/stage/orientation", |b| {
        b.iter(|| {
            let mut s = 0.0;
            for l in 0..scale.n_levels {
                for &i in &kept[l] {
                    let k = corners[l][i];
                    s += ic_angle(&pyr.levels[l], &patch, k.x as usize, k.y as usize);
                }
            }
            s
        })
    });

    let mut blurred: Vec<GrayImage> = vec![GrayImage::new(0, 0); scale.n_levels];
    let mut tmp = Vec::new();
    c.bench_function("orb/stage/blur", |b| {
        b.iter(|| {
            for (level, out) in pyr.levels.iter().zip(blurred.iter_mut()) {
                gaussian_blur(level, out, &mut tmp);
            }
        })
    });
    c.bench_function("orb/stage/descriptors", |b| {
        b.iter(|| {
            let mut acc = 0u64;
            for l in 0..scale.n_levels {
                for &i in &kept[l] {
                    let k = corners[l][i];
                    acc ^= compute_descriptor(&blurred[l], k.x as usize, k.y as usize, 37.0)[0];
                }
            }
            acc
        })
    });
}

fn stereo(c: &mut Criterion) {
    let scene = TestScene::random(752.0, 480.0, 450, 3);
    let left = scene.render(752, 480, |u, v| (u, v));
    let right = scene.render(752, 480, |u, v| (u + 20.0 + 0.03 * v, v));
    let camera = Camera::euroc_rectified();
    let input = FrameInput {
        timestamp: 0.0,
        image: Arc::new(left),
        depth: None,
        right: Some(Arc::new(right)),
    };
    let mut ex = OrbExtractor::new(OrbConfig::stereo());
    let f = Frame::new(0, &input, &camera, &mut ex);
    eprintln!(
        "stereo frame: {} keypoints, {} with depth",
        f.len(),
        f.n_with_depth()
    );
    c.bench_function("frame/stereo_752x480", |b| {
        b.iter(|| Frame::new(0, black_box(&input), &camera, &mut ex))
    });
    c.bench_function("orb/extract_752x480_1200", |b| {
        b.iter(|| ex.extract(black_box(&input.image)))
    });
}

criterion_group!(benches, stages, stereo);
criterion_main!(benches);
