//! Benchmarks: a full ATE evaluation (association + Umeyama + statistics) of a 100k-pose pair,
//! and the association alone on stamps packed into one association window (every estimate
//! stamp within max_difference of every ground-truth stamp: the worst case of the greedy
//! TUM pairing, whose candidate pairs are all pairs).

use ate_eval::{associate, evaluate_ate, AssociationMode, AteOptions, Trajectory};
use criterion::{criterion_group, criterion_main, Criterion, SamplingMode};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};

fn pair(n: usize) -> (Trajectory, Trajectory) {
    let mut gt = Trajectory::new();
    let mut est = Trajectory::new();
    for i in 0..n {
        let a = i as f64 * 1e-3;
        let q = UnitQuaternion::from_euler_angles(0.1 * a.sin(), 0.2 * a.cos(), a);
        gt.push(
            i as f64 / 30.0,
            Isometry3::from_parts(Translation3::new(a.cos(), a.sin(), 0.1 * a), q),
        );
        let jitter = ((i * 7919) % 13) as f64 * 1e-3;
        est.push(
            i as f64 / 30.0 + jitter,
            Isometry3::from_parts(Translation3::new(a.cos() + 0.01, a.sin(), 0.1 * a + 2.0), q),
        );
    }
    (gt, est)
}

/// `n` ground-truth and `n` estimate stamps 1 us apart (n <= 10 000: all within 10 ms, inside
/// one 20 ms window), each estimate 0.3 us after its ground truth.
fn one_window(n: usize) -> (Vec<f64>, Vec<f64>) {
    let gt: Vec<f64> = (0..n).map(|k| 1_305_031_102.0 + k as f64 * 1e-6).collect();
    let est: Vec<f64> = gt.iter().map(|t| t + 3e-7).collect();
    (gt, est)
}

fn bench(c: &mut Criterion) {
    let (gt, est) = pair(100_000);
    c.bench_function("ate_100k_tum_assoc", |b| {
        b.iter(|| evaluate_ate(&gt, &est, &AteOptions::default()).unwrap())
    });
    let evo = AteOptions {
        association: AssociationMode::Evo,
        ..Default::default()
    };
    c.bench_function("ate_100k_evo_assoc", |b| {
        b.iter(|| evaluate_ate(&gt, &est, &evo).unwrap())
    });

    let mut g = c.benchmark_group("associate_one_window");
    g.sampling_mode(SamplingMode::Flat);
    for n in [1_000, 10_000] {
        let (gt, est) = one_window(n);
        for (name, mode) in [("tum", AssociationMode::Tum), ("evo", AssociationMode::Evo)] {
            g.bench_function(format!("{name}_{}_stamps", 2 * n), |b| {
                b.iter(|| {
                    let pairs = associate(&gt, &est, 0.02, 0.0, mode);
                    assert_eq!(pairs.len(), n);
                    pairs
                })
            });
        }
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
