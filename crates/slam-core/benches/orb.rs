//! ORB front-end benchmarks: whole extraction on a 640x480 frame, each stage alone (pyramid,
//! FAST, distribution, orientation, blur, descriptors), the same on a densely textured 640x480
//! frame (many more FAST responses per cell), and stereo frame construction on a 752x480 pair.
//! Single thread. Run with `cargo bench -p slam-core --bench orb`.
//!
//! With `NF_BENCH_ONCE=orb` (or `orb_dense`) the binary instead extracts the test frame (or the
//! dense frame) `NF_BENCH_REPEAT` times (default 1), prints the fastest and the median time and
//! a fingerprint of the keypoints and descriptors: a short run for `valgrind --tool=callgrind`
//! and a bit-identity check.

use std::hint::black_box;
use std::sync::Arc;

use criterion::{criterion_group, Criterion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slam_core::feature::brief::{compute_descriptor, gaussian_blur};
use slam_core::feature::distribute::{distribute, QuadScratch};
use slam_core::feature::extractor::detect_level;
use slam_core::feature::fast::{Corner, FastScratch};
use slam_core::feature::orientation::{ic_angle, CirclePatch};
use slam_core::feature::test_scene::{test_frame, TestScene};
use slam_core::feature::{OrbConfig, OrbExtractor, Pyramid, EDGE_THRESHOLD};
use slam_core::frame::Frame;
use slam_core::{Camera, FrameInput, GrayImage};

/// A densely textured 640x480 frame, the same every run: a collage of 16 x 16 tiles, each
/// with its own mean, contrast (20 to 140 grey levels) and grain (1 to 3 pixels) of uniform
/// noise, so FAST fires all over the image at every pyramid level (unlike the mostly flat
/// shapes of [`test_frame`]).
fn dense_frame() -> GrayImage {
    let (w, h) = (640, 480);
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let tile = 16;
    let tiles: Vec<(f64, f64, usize)> = (0..(w / tile) * (h / tile))
        .map(|_| {
            (
                rng.random_range(60.0..196.0),
                rng.random_range(20.0..140.0),
                rng.random_range(1..=3),
            )
        })
        .collect();
    // Noise on a 1-pixel lattice; a tile of grain g reads it at (x / g, y / g).
    let noise: Vec<f64> = (0..w * h).map(|_| rng.random_range(-0.5..0.5)).collect();
    let mut img = GrayImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let (mean, contrast, grain) = tiles[(y / tile) * (w / tile) + x / tile];
            let n = noise[(y / grain) * w + x / grain];
            img.data[y * w + x] = (mean + contrast * n).round().clamp(0.0, 255.0) as u8;
        }
    }
    img
}

fn dense(c: &mut Criterion) {
    let img = dense_frame();
    let cfg = OrbConfig::default();
    let mut ex = OrbExtractor::new(cfg.clone());
    eprintln!("dense frame: {} keypoints", ex.extract(&img).0.len());
    c.bench_function("orb/extract_640x480_dense", |b| {
        b.iter(|| ex.extract(black_box(&img)))
    });
    let scale = ex.scale_info().clone();
    let mut pyr = Pyramid::new();
    pyr.build(&img, &scale);
    let mut fast = FastScratch::default();
    let mut counts = Vec::new();
    let mut corners: Vec<Vec<Corner>> = vec![Vec::new(); scale.n_levels];
    // Detected once here as well, so that the distribution stage has its input when the FAST
    // stage is filtered out.
    for (l, out) in corners.iter_mut().enumerate() {
        detect_level(&pyr.levels[l], 20, 7, &mut fast, &mut counts, out);
    }
    c.bench_function("orb/stage/fast_dense", |b| {
        b.iter(|| {
            for (l, out) in corners.iter_mut().enumerate() {
                out.clear();
                detect_level(&pyr.levels[l], 20, 7, &mut fast, &mut counts, out);
            }
        })
    });
    let n_corners: usize = corners.iter().map(|c| c.len()).sum();
    eprintln!("dense frame: FAST corners over all levels: {n_corners}");
    let per_level = cfg.features_per_level();
    let mut quad = QuadScratch::default();
    let mut kept: Vec<Vec<usize>> = vec![Vec::new(); scale.n_levels];
    c.bench_function("orb/stage/distribute_dense", |b| {
        b.iter(|| {
            for l in 0..scale.n_levels {
                let e = (EDGE_THRESHOLD - 3) as f32;
                let level = &pyr.levels[l];
                let bx = (e, e, level.width as f32 - e, level.height as f32 - e);
                distribute(&corners[l], bx, per_level[l], &mut quad, &mut kept[l]);
            }
        })
    });
}

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
        colour: None,
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

/// One extractor on the test frame or the dense frame, `NF_BENCH_REPEAT` times.
fn extract_once(dense: bool) {
    let img = if dense { dense_frame() } else { test_frame(1) };
    let mut ex = OrbExtractor::new(OrbConfig::default());
    let repeat: usize = std::env::var("NF_BENCH_REPEAT")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(1)
        .max(1);
    let mut times = Vec::new();
    let mut result = None;
    for _ in 0..repeat {
        let t = std::time::Instant::now();
        result = Some(black_box(ex.extract(&img)));
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    let (keypoints, descriptors) = result.expect("at least one run");
    // FNV-1a over every keypoint field and descriptor word.
    let mut h = slam_core::hash::FNV1A_OFFSET;
    let mut eat = |w: u64| h = slam_core::hash::fnv1a_continue(h, &w.to_le_bytes());
    for k in &keypoints {
        eat(format!("{k:?}").len() as u64);
        for b in format!("{k:?}").bytes() {
            eat(u64::from(b));
        }
    }
    for d in &descriptors {
        for b in format!("{d:?}").bytes() {
            eat(u64::from(b));
        }
    }
    println!(
        "extract x {repeat}: fastest {:.3} ms, median {:.3} ms; {} keypoints, fingerprint {h:016x}",
        times[0],
        times[times.len() / 2],
        keypoints.len()
    );
}

criterion_group!(benches, stages, dense, stereo);

fn main() {
    match std::env::var("NF_BENCH_ONCE").as_deref() {
        Ok("orb") => extract_once(false),
        Ok("orb_dense") => extract_once(true),
        Ok(other) => panic!("NF_BENCH_ONCE={other}: only orb and orb_dense run once"),
        Err(_) => {
            benches();
            Criterion::default().configure_from_args().final_summary();
        }
    }
}
