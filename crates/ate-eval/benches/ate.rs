//! Benchmark: a full ATE evaluation (association + Umeyama + statistics) of a 100k-pose pair.

use ate_eval::{evaluate_ate, AssociationMode, AteOptions, Trajectory};
use criterion::{criterion_group, criterion_main, Criterion};
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
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
