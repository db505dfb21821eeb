//! Benchmarks of the solvers at ORB-SLAM2's working sizes, single thread: pose-only
//! optimization of a frame with 500 matches (10 % mismatches), local bundle adjustment of
//! 20 keyframes / 2000 points / ~15k observations (60 % RGB-D, 40 % monocular keypoints) and of
//! the wide window of a run that failed on moving people (120 mutually covisible keyframes,
//! 6000 points tracked over up to 100 of them), and,
//! for loop closing, the essential graph (20 iterations) and a global bundle adjustment (10
//! iterations, robust) over a circuit of 400 keyframes that flies over its first quarter again
//! (15k points on the walls of a room, feature tracks of 4-20 keyframes).
//!
//! Run: `flock /tmp/nf-cargo.lock cargo bench -p slam-core --bench optimize`.
//!
//! With `NF_BENCH_ONCE=local_ba` (or `local_ba_wide`) in the environment the benchmark binary
//! instead solves that local BA problem once and prints a fingerprint of its result (every bit
//! of the refined poses and points, the outliers and the costs), which makes a cheap
//! bit-identity check and a short run to count instructions under `valgrind --tool=callgrind`;
//! `NF_BENCH_REPEAT=n` times `n` runs before that and prints the fastest and the median.

use criterion::{criterion_group, BatchSize, Criterion};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use slam_core::optimize::{
    local_bundle_adjustment, optimize_pose_graph, pose_optimization, BaConfig, BaKeyFrame,
    BaObservation, BaPoint, BaProblem, Measurement, PoseGraph, PoseGraphEdge, PoseObservation,
    PoseOptConfig,
};
use slam_core::Camera;
use std::collections::BTreeMap;
use std::time::Instant;

/// A standard normal sample (Box-Muller).
fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.random::<f64>().max(1e-300);
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// A pose near `tcw`: camera centre moved by `metres`, orientation turned by `radians`.
fn perturb(
    tcw: &Isometry3<f64>,
    metres: f64,
    radians: f64,
    rng: &mut ChaCha8Rng,
) -> Isometry3<f64> {
    let dir = Vector3::new(gaussian(rng), gaussian(rng), gaussian(rng)).normalize();
    let axis = Vector3::new(gaussian(rng), gaussian(rng), gaussian(rng)).normalize();
    let twc = tcw.inverse();
    Isometry3::from_parts(
        Translation3::from(twc.translation.vector + dir * metres),
        twc.rotation * UnitQuaternion::from_scaled_axis(axis * radians),
    )
    .inverse()
}

/// A noisy keypoint of `pw` seen from `tcw` (1 px x octave scale), or `None` if not visible.
fn observe(
    camera: &Camera,
    tcw: &Isometry3<f64>,
    pw: &Vector3<f64>,
    rng: &mut ChaCha8Rng,
) -> Option<(Measurement, f64)> {
    let p = (tcw * Point3::from(*pw)).coords;
    if p.z < 0.1 {
        return None;
    }
    let uv = camera.project(&p);
    if !camera.in_image(uv.x, uv.y) {
        return None;
    }
    let octave = rng.random_range(0..4);
    let sigma = 1.2f64.powi(octave);
    let (u, v) = (uv.x + sigma * gaussian(rng), uv.y + sigma * gaussian(rng));
    let m = if rng.random_bool(0.6) {
        Measurement::rgbd(camera, u, v, p.z * (1.0 + 0.01 * gaussian(rng)))
    } else {
        Measurement::Mono { u, v }
    };
    Some((m, 1.0 / (sigma * sigma)))
}

fn pose_only_input(camera: &Camera) -> (Isometry3<f64>, Vec<PoseObservation>) {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let tcw = Isometry3::from_parts(
        Translation3::new(0.1, -0.2, 0.3),
        UnitQuaternion::from_euler_angles(0.1, 0.2, -0.1),
    );
    let twc = tcw.inverse();
    let mut obs = Vec::new();
    while obs.len() < 500 {
        let p_c = camera.unproject(
            rng.random_range(0.0..640.0),
            rng.random_range(0.0..480.0),
            rng.random_range(0.8..6.0),
        );
        let pw = (twc * Point3::from(p_c)).coords;
        let Some((mut measurement, inv_sigma2)) = observe(camera, &tcw, &pw, &mut rng) else {
            continue;
        };
        if rng.random_bool(0.1) {
            measurement = Measurement::Mono {
                u: rng.random_range(0.0..640.0),
                v: rng.random_range(0.0..480.0),
            };
        }
        obs.push(PoseObservation {
            point_world: pw,
            measurement,
            inv_sigma2,
        });
    }
    (perturb(&tcw, 0.03, 1f64.to_radians(), &mut rng), obs)
}

/// A local BA window: `n_kf` keyframes along a 2 m line, looking ahead, and `n_points` points,
/// each tracked over a run of 3..=`max_track` consecutive keyframes (noise on both).
fn local_ba_input(camera: &Camera, n_kf: usize, n_points: usize, max_track: usize) -> BaProblem {
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let gt: Vec<Isometry3<f64>> = (0..n_kf)
        .map(|i| {
            let s = i as f64 / (n_kf - 1) as f64;
            let centre = Vector3::new(
                -1.0 + 2.0 * s,
                0.05 * gaussian(&mut rng),
                0.1 * gaussian(&mut rng),
            );
            let rot = UnitQuaternion::from_euler_angles(
                0.02 * gaussian(&mut rng),
                0.2 * (s - 0.5),
                0.02 * gaussian(&mut rng),
            );
            Isometry3::from_parts(Translation3::from(centre), rot).inverse()
        })
        .collect();
    let mut problem = BaProblem::default();
    while problem.points.len() < n_points {
        let pw = Vector3::new(
            rng.random_range(-3.0..3.0),
            rng.random_range(-1.5..1.5),
            rng.random_range(2.0..6.0),
        );
        // A track over a run of consecutive keyframes (20 keyframes: 3..=14, ~8.5 on average).
        let len = rng.random_range(3..=max_track);
        let start = rng.random_range(0..=n_kf - len);
        let j = problem.points.len();
        let before = problem.observations.len();
        for (k, tcw) in gt.iter().enumerate().skip(start).take(len) {
            if let Some((measurement, inv_sigma2)) = observe(camera, tcw, &pw, &mut rng) {
                problem.observations.push(BaObservation {
                    keyframe: k,
                    point: j,
                    measurement,
                    inv_sigma2,
                });
            }
        }
        if problem.observations.len() - before < 2 {
            problem.observations.truncate(before);
            continue;
        }
        let noise = Vector3::new(gaussian(&mut rng), gaussian(&mut rng), gaussian(&mut rng)) * 0.03;
        problem.points.push(BaPoint {
            position: pw + noise,
        });
    }
    problem.keyframes = gt
        .iter()
        .enumerate()
        .map(|(k, t)| BaKeyFrame {
            tcw: if k == 0 {
                *t
            } else {
                perturb(t, 0.01, 0.5f64.to_radians(), &mut rng)
            },
            fixed: k == 0,
        })
        .collect();
    problem
}

/// Name of the wide-window local BA benchmark.
const WIDE_WINDOW: &str = "120kf_6000pts_all_covisible";

/// The window of a run whose tracking has failed on moving people: the camera hardly moves and
/// inserts keyframe after keyframe, all of which see each other, so ORB-SLAM2's local window
/// (every covisible keyframe) holds over a hundred of them and the reduced camera system is
/// dense.
fn wide_window_input(camera: &Camera) -> BaProblem {
    local_ba_input(camera, 120, 6000, 100)
}

/// Keyframes of the circuit: 1.25 turns, so the last 80 fly over the first ones again.
const CIRCUIT_KEYFRAMES: usize = 400;

/// A circuit round a room (camera centres on a 1.5 m circle, looking out at walls 4 m from the
/// centre): the true poses, a global BA problem over them (poses drifted, the first fixed) and
/// the essential graph of the map (spanning tree plus every pair of keyframes sharing at least
/// 100 points, measured at the truth; the poses start with the accumulated drift).
fn circuit_input(camera: &Camera) -> (BaProblem, PoseGraph) {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let n = CIRCUIT_KEYFRAMES;
    let heading = |k: usize| std::f64::consts::TAU * 1.25 * k as f64 / n as f64;
    let gt: Vec<Isometry3<f64>> = (0..n)
        .map(|k| {
            let a = heading(k);
            let centre = Vector3::new(1.5 * a.cos(), 0.05 * gaussian(&mut rng), 1.5 * a.sin());
            let z = Vector3::new(a.cos(), 0.0, a.sin());
            let y = Vector3::y();
            let rot = nalgebra::Rotation3::from_basis_unchecked(&[y.cross(&z), y, z]);
            let wobble = UnitQuaternion::from_euler_angles(
                0.02 * gaussian(&mut rng),
                0.02 * gaussian(&mut rng),
                0.02 * gaussian(&mut rng),
            );
            Isometry3::from_parts(
                Translation3::from(centre),
                UnitQuaternion::from_rotation_matrix(&rot) * wobble,
            )
            .inverse()
        })
        .collect();
    let mut problem = BaProblem::default();
    let mut shared: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    while problem.points.len() < 15_000 {
        let phi = rng.random_range(0.0..std::f64::consts::TAU);
        let pw = Vector3::new(
            4.0 * phi.cos(),
            rng.random_range(-1.5..1.5),
            4.0 * phi.sin(),
        );
        // Each pass of the circuit by the point gives a track over a run of consecutive
        // keyframes that see it.
        let visible: Vec<usize> = (0..n)
            .filter(|&k| {
                let p = gt[k] * Point3::from(pw);
                p.z > 0.1
                    && camera.in_image(camera.project(&p.coords).x, camera.project(&p.coords).y)
            })
            .collect();
        let mut track = Vec::new();
        for pass in visible.chunk_by(|a, b| b - a == 1) {
            let len = rng.random_range(4..=20).min(pass.len());
            let start = rng.random_range(0..=pass.len() - len);
            track.extend_from_slice(&pass[start..start + len]);
        }
        let j = problem.points.len();
        let before = problem.observations.len();
        for &k in &track {
            if let Some((measurement, inv_sigma2)) = observe(camera, &gt[k], &pw, &mut rng) {
                problem.observations.push(BaObservation {
                    keyframe: k,
                    point: j,
                    measurement,
                    inv_sigma2,
                });
            }
        }
        if problem.observations.len() - before < 2 {
            problem.observations.truncate(before);
            continue;
        }
        for (a, oa) in problem.observations[before..].iter().enumerate() {
            for ob in &problem.observations[before + a + 1..] {
                *shared.entry((oa.keyframe, ob.keyframe)).or_default() += 1;
            }
        }
        let noise = Vector3::new(gaussian(&mut rng), gaussian(&mut rng), gaussian(&mut rng)) * 0.03;
        problem.points.push(BaPoint {
            position: pw + noise,
        });
    }
    // Drift that grows along the circuit, as odometry leaves it before the loop closes.
    let mut drifted = gt.clone();
    for k in 1..n {
        let step = gt[k] * gt[k - 1].inverse();
        drifted[k] = perturb(
            &(step * drifted[k - 1]),
            0.002,
            0.1f64.to_radians(),
            &mut rng,
        );
    }
    problem.keyframes = drifted
        .iter()
        .enumerate()
        .map(|(k, &tcw)| BaKeyFrame { tcw, fixed: k == 0 })
        .collect();
    let mut edges: Vec<PoseGraphEdge> = (1..n)
        .map(|k| PoseGraphEdge {
            i: k,
            j: k - 1,
            t_ij: gt[k] * gt[k - 1].inverse(),
        })
        .collect();
    for (&(a, b), &count) in &shared {
        if count >= 100 && a.abs_diff(b) > 1 {
            edges.push(PoseGraphEdge {
                i: b.max(a),
                j: b.min(a),
                t_ij: gt[b.max(a)] * gt[b.min(a)].inverse(),
            });
        }
    }
    let mut fixed = vec![false; n];
    fixed[0] = true;
    let graph = PoseGraph {
        poses: drifted,
        fixed,
        edges,
    };
    (problem, graph)
}

fn bench_optimize(c: &mut Criterion) {
    let camera = Camera::tum_fr3();
    let (start, obs) = pose_only_input(&camera);
    let cfg = PoseOptConfig::default();
    c.bench_function("pose_only_500_obs", |b| {
        b.iter(|| pose_optimization(&camera, &start, &obs, &cfg))
    });

    let ba_cfg = BaConfig::default();
    let mut group = c.benchmark_group("local_ba");
    group.sample_size(20);
    for (name, problem) in [
        ("20kf_2000pts", local_ba_input(&camera, 20, 2000, 14)),
        (WIDE_WINDOW, wide_window_input(&camera)),
    ] {
        eprintln!(
            "local BA problem {name}: {} keyframes, {} points, {} observations",
            problem.keyframes.len(),
            problem.points.len(),
            problem.observations.len()
        );
        group.bench_function(name, |b| {
            b.iter_batched(
                || problem.clone(),
                |mut p| local_bundle_adjustment(&camera, &mut p, &ba_cfg),
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();

    let (problem, graph) = circuit_input(&camera);
    let gba_cfg = BaConfig {
        first_pass_iterations: 10,
        second_pass_iterations: 0,
    };
    eprintln!(
        "circuit: {} keyframes, {} points, {} observations; essential graph of {} edges",
        problem.keyframes.len(),
        problem.points.len(),
        problem.observations.len(),
        graph.edges.len()
    );
    let t = Instant::now();
    let report = optimize_pose_graph(&mut graph.clone(), 20);
    eprintln!(
        "essential graph once: {:.3} s, cost {:.3e} -> {:.3e} in {} iterations",
        t.elapsed().as_secs_f64(),
        report.initial_cost,
        report.final_cost,
        report.iterations
    );
    let t = Instant::now();
    let report = local_bundle_adjustment(&camera, &mut problem.clone(), &gba_cfg);
    eprintln!(
        "global BA once: {:.3} s, chi2 {:.4e} -> {:.4e} in {} iterations",
        t.elapsed().as_secs_f64(),
        report.initial_cost,
        report.final_cost,
        report.iterations
    );
    let mut group = c.benchmark_group("loop_closing_400kf");
    group.sample_size(10);
    group.bench_function("essential_graph", |b| {
        b.iter_batched(
            || graph.clone(),
            |mut g| optimize_pose_graph(&mut g, 20),
            BatchSize::LargeInput,
        )
    });
    group.bench_function("global_ba", |b| {
        b.iter_batched(
            || problem.clone(),
            |mut p| local_bundle_adjustment(&camera, &mut p, &gba_cfg),
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

/// FNV-1a over 64-bit words.
fn fingerprint(words: impl IntoIterator<Item = u64>) -> u64 {
    words
        .into_iter()
        .fold(slam_core::hash::FNV1A_OFFSET, |h, w| {
            slam_core::hash::fnv1a_continue(h, &w.to_le_bytes())
        })
}

/// One local BA on a benchmark problem (`wide`: the 120-keyframe window); prints the fingerprint
/// of its result.
fn local_ba_once(wide: bool) {
    let camera = Camera::tum_fr3();
    let input = if wide {
        wide_window_input(&camera)
    } else {
        local_ba_input(&camera, 20, 2000, 14)
    };
    // NF_BENCH_REPEAT=n: also time n more runs and print the fastest and the median (robust to a
    // busy machine, unlike a mean).
    let repeat: usize = std::env::var("NF_BENCH_REPEAT")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(0);
    let mut times: Vec<f64> = (0..repeat)
        .map(|_| {
            let mut p = input.clone();
            let t = Instant::now();
            std::hint::black_box(local_bundle_adjustment(
                &camera,
                &mut p,
                &BaConfig::default(),
            ));
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    if !times.is_empty() {
        println!(
            "local BA x {repeat}: fastest {:.2} ms, median {:.2} ms",
            times[0],
            times[times.len() / 2]
        );
    }
    let mut problem = input;
    let report = local_bundle_adjustment(&camera, &mut problem, &BaConfig::default());
    let mut words: Vec<u64> = Vec::new();
    for kf in &problem.keyframes {
        words.extend(kf.tcw.rotation.coords.iter().map(|x| x.to_bits()));
        words.extend(kf.tcw.translation.vector.iter().map(|x| x.to_bits()));
    }
    for p in &problem.points {
        words.extend(p.position.iter().map(|x| x.to_bits()));
    }
    words.extend(report.outliers.iter().map(|&o| u64::from(o)));
    words.extend(report.pass_costs.iter().flatten().map(|c| c.to_bits()));
    words.push(report.final_cost.to_bits());
    println!(
        "local BA: {} iterations, chi2 {:.6e} -> {:.6e}, {} outliers, fingerprint {:016x}",
        report.iterations,
        report.initial_cost,
        report.final_cost,
        report.outliers.iter().filter(|&&o| o).count(),
        fingerprint(words)
    );
}

criterion_group!(benches, bench_optimize);

fn main() {
    match std::env::var("NF_BENCH_ONCE").as_deref() {
        Ok("local_ba") => local_ba_once(false),
        Ok("local_ba_wide") => local_ba_once(true),
        Ok(other) => panic!("NF_BENCH_ONCE={other}: only local_ba and local_ba_wide run once"),
        Err(_) => {
            benches();
            Criterion::default().configure_from_args().final_summary();
        }
    }
}
