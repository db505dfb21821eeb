//! The keypoint area search of matching by projection and the map-point fuse
//! (`Features::features_in_area`, ORB-SLAM2's 64 x 48 cell grid) against a k-d tree (kiddo's
//! `ImmutableKdTree`, the package the project's design names) on the same keypoints: building
//! the structure once per frame, and one query at the window sizes the matchers use. Both
//! return the same indices (checked before timing), so a switch would change no trajectory;
//! the figures decide (docs/architecture.md, "Packages").
//! Run: `cargo bench -p slam-core --bench area_search`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use kiddo::ImmutableKdTree;
use kiddo::SquaredEuclidean;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slam_core::data::FeatureGrid;
use slam_core::feature::KeyPoint;
use slam_core::Camera;
use std::hint::black_box;

/// `n` keypoints over a 640 x 480 image, clustered as ORB's are (textured patches hold most of
/// them), on 8 pyramid levels.
fn keypoints(n: usize, seed: u64) -> Vec<KeyPoint> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let centres: Vec<(f32, f32)> = (0..40)
        .map(|_| (rng.random_range(0.0..640.0), rng.random_range(0.0..480.0)))
        .collect();
    (0..n)
        .map(|_| {
            let (x, y) = if rng.random_bool(0.7) {
                let c = centres[rng.random_range(0..centres.len())];
                (
                    (c.0 + rng.random_range(-40.0..40.0)).clamp(0.0, 639.0),
                    (c.1 + rng.random_range(-40.0..40.0)).clamp(0.0, 479.0),
                )
            } else {
                (rng.random_range(0.0..640.0), rng.random_range(0.0..480.0))
            };
            KeyPoint {
                x,
                y,
                octave: rng.random_range(0..8),
                angle: 0.0,
                response: 1.0,
            }
        })
        .collect()
}

/// The k-d tree's answer to the grid's query: keypoints in the square of half-side `r` around
/// (x, y) (a disc of radius r sqrt 2, then the square's test), ascending.
fn kd_in_area(
    tree: &ImmutableKdTree<f64, 2>,
    kps: &[KeyPoint],
    x: f64,
    y: f64,
    r: f64,
) -> Vec<usize> {
    let mut out: Vec<usize> = tree
        .within_unsorted::<SquaredEuclidean>(&[x, y], 2.0 * r * r)
        .into_iter()
        .map(|n| n.item as usize)
        .filter(|&i| (kps[i].x as f64 - x).abs() < r && (kps[i].y as f64 - y).abs() < r)
        .collect();
    out.sort_unstable();
    out
}

/// The grid's query without the level filter, as `Features::features_in_area` runs it.
fn grid_in_area(features: &slam_core::data::Features, x: f64, y: f64, r: f64) -> Vec<usize> {
    features.features_in_area(x, y, r, 0, -1)
}

fn bench_area_search(c: &mut Criterion) {
    let camera = Camera::tum_fr3();
    let mut g = c.benchmark_group("area_search");
    g.sample_size(20);
    for n in [1000usize, 2000] {
        let kps = keypoints(n, n as u64);
        let points: Vec<[f64; 2]> = kps.iter().map(|k| [k.x as f64, k.y as f64]).collect();
        let features = slam_core::data::Features::new(
            kps.clone(),
            vec![[0u64; 4]; n],
            vec![0.0; n],
            vec![-1.0; n],
            &camera,
        );
        let tree: ImmutableKdTree<f64, 2> = ImmutableKdTree::new_from_slice(&points);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let queries: Vec<(f64, f64)> = (0..512)
            .map(|_| (rng.random_range(0.0..640.0), rng.random_range(0.0..480.0)))
            .collect();
        // The same answers, or the comparison means nothing.
        for r in [7.5, 15.0, 30.0, 100.0] {
            for &(x, y) in &queries {
                assert_eq!(
                    grid_in_area(&features, x, y, r),
                    kd_in_area(&tree, &kps, x, y, r),
                    "n {n}, r {r} at ({x}, {y})"
                );
            }
        }
        g.bench_function(BenchmarkId::new("build_grid", n), |b| {
            b.iter(|| FeatureGrid::new(black_box(&kps), &camera))
        });
        g.bench_function(BenchmarkId::new("build_kdtree", n), |b| {
            b.iter(|| ImmutableKdTree::<f64, 2>::new_from_slice(black_box(&points)))
        });
        for r in [7.5, 15.0, 30.0, 100.0] {
            g.bench_function(BenchmarkId::new(format!("query_grid_r{r}"), n), |b| {
                b.iter(|| {
                    queries
                        .iter()
                        .map(|&(x, y)| grid_in_area(&features, x, y, r).len())
                        .sum::<usize>()
                })
            });
            g.bench_function(BenchmarkId::new(format!("query_kdtree_r{r}"), n), |b| {
                b.iter(|| {
                    queries
                        .iter()
                        .map(|&(x, y)| kd_in_area(&tree, &kps, x, y, r).len())
                        .sum::<usize>()
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench_area_search);
criterion_main!(benches);
