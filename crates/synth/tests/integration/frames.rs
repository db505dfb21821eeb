//! Properties of generated frames: exact geometry, the depth noise model's components,
//! determinism, texture richness (FAST corners), moving-object coverage, occlusion, stereo.

use nalgebra::Point3;
use slam_core::feature::fast::CIRCLE;
use synth::{
    AxialNoise, DepthLag, DepthNoise, Generator, LateralNoise, MovingObjects, SynthConfig,
    SystematicDistortion,
};

fn clean_with(noise: DepthNoise) -> SynthConfig {
    SynthConfig {
        depth_noise: noise,
        ..SynthConfig::preset("clean").unwrap()
    }
}

/// The noiseless depth back-projected with the ground-truth pose lands on the scene geometry.
#[test]
fn noiseless_depth_backprojects_onto_the_scene_sub_mm() {
    let mut cfg = SynthConfig::preset("clean").unwrap();
    cfg.moving_objects = Some(MovingObjects::default());
    for traj in [
        synth::Trajectory::Xyz,
        synth::Trajectory::Spin,
        synth::Trajectory::Loop,
    ] {
        cfg.trajectory = traj.clone();
        let gen = Generator::new(cfg.clone(), 5);
        let cam = gen.camera();
        for i in [0usize, 77, 211] {
            let f = gen.frame(i);
            let placed = gen.scene().place(gen.time(i));
            let d = f.depth_true.as_ref().unwrap();
            let mut worst = 0.0f64;
            for v in (0..d.height).step_by(5) {
                for u in (0..d.width).step_by(5) {
                    let z = d.get(u, v).expect("closed room: every pixel has depth") as f64;
                    let pc = cam.unproject(u as f64, v as f64, z);
                    let pw = f.pose_wc * Point3::from(pc);
                    worst = worst.max(gen.scene().surface_distance(&placed, &pw.coords));
                }
            }
            assert!(
                worst < 1e-3,
                "{traj:?} frame {i}: {worst} m off the surfaces"
            );
            // The measured (clean) depth is the true depth at the PNG resolution.
            let m = f.depth.as_ref().unwrap();
            for (a, b) in m.data.iter().zip(&d.data) {
                assert!((a - b).abs() <= 1.0e-4 + 1e-6, "{a} vs {b}");
            }
        }
    }
}

/// Measured axial noise std at 1, 2 and 3 m (pixels within 5 cm of those depths, collected
/// over frames with a person walking close by) is within 10 % of the model.
#[test]
fn axial_noise_std_within_10_percent_at_1_2_3_m() {
    let axial = AxialNoise {
        grazing: false,
        ..AxialNoise::default()
    };
    let mut cfg = clean_with(DepthNoise {
        axial: Some(axial.clone()),
        ..DepthNoise::default()
    });
    cfg.moving_objects = Some(MovingObjects::default());
    let gen = Generator::new(cfg, 2);
    let targets = [1.0f64, 2.0, 3.0];
    let mut sums = [(0usize, 0.0f64, 0.0f64); 3];
    for i in (0..270).step_by(30) {
        let f = gen.frame(i);
        let (m, t) = (f.depth.unwrap(), f.depth_true.unwrap());
        for (a, b) in m.data.iter().zip(&t.data) {
            for (k, z) in targets.iter().enumerate() {
                if (*b as f64 - z).abs() < 0.05 {
                    let e = (*a - *b) as f64;
                    let s = &mut sums[k];
                    s.0 += 1;
                    s.1 += e * e;
                    s.2 += axial.sigma(*b as f64, 0.0).powi(2);
                }
            }
        }
    }
    for (k, z) in targets.iter().enumerate() {
        let (n, se, sm) = sums[k];
        assert!(n > 3000, "{n} samples at {z} m");
        let ratio = (se / sm).sqrt();
        assert!(
            (ratio - 1.0).abs() < 0.10,
            "at {z} m: measured / model std = {ratio} ({n} px)"
        );
    }
}

/// Lateral noise mixes depths at boundaries and leaves flat interiors alone.
#[test]
fn lateral_mixing_at_boundaries_not_on_interiors() {
    let gen = Generator::new(
        clean_with(DepthNoise {
            lateral: Some(LateralNoise::default()),
            ..DepthNoise::default()
        }),
        3,
    );
    let f = gen.frame(40);
    let (m, t) = (f.depth.unwrap(), f.depth_true.unwrap());
    let (w, h) = (t.width, t.height);
    let z = |x: usize, y: usize| t.data[y * w + x] as f64;
    let (mut boundary, mut mixed_boundary, mut interior, mut interior_bad) = (0, 0, 0, 0);
    let r = 5;
    for y in r..h - r {
        for x in r..w - r {
            let e = (m.data[y * w + x] as f64 - z(x, y)).abs();
            let jump = [(1i64, 0i64), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .map(|&(dx, dy)| {
                    (z((x as i64 + dx) as usize, (y as i64 + dy) as usize) - z(x, y)).abs()
                })
                .fold(0.0, f64::max);
            if jump > 0.2 {
                boundary += 1;
                mixed_boundary += (e > 0.1) as usize;
            }
            let (mut lo, mut hi) = (f64::MAX, f64::MIN);
            for yy in y - r..=y + r {
                for xx in x - r..=x + r {
                    lo = lo.min(z(xx, yy));
                    hi = hi.max(z(xx, yy));
                }
            }
            if hi - lo < 0.02 {
                // A flat interior: any neighbour's depth is within hi - lo of this one.
                interior += 1;
                interior_bad += (e > hi - lo + 1.1e-4) as usize;
            }
        }
    }
    assert!(
        boundary > 500 && interior > 10_000,
        "{boundary} boundary, {interior} interior px"
    );
    let frac = mixed_boundary as f64 / boundary as f64;
    assert!(frac > 0.15, "only {frac} of boundary pixels mixed");
    assert_eq!(interior_bad, 0, "lateral noise changed flat interiors");
}

/// Same (config, seed, index) gives the same bytes in any order and with any thread count;
/// another seed gives other bytes.
#[test]
fn frames_are_deterministic_across_order_and_threads() {
    let cfg = SynthConfig::preset("walking").unwrap();
    let a = Generator::new(cfg.clone(), 9);
    let b = Generator::new(cfg.clone(), 9);
    let f5 = a.frame(5);
    let _ = b.frame(2);
    let g5 = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| b.frame(5));
    assert_eq!(f5.rgb, g5.rgb);
    assert_eq!(f5.gray, g5.gray);
    assert_eq!(f5.depth, g5.depth);
    assert_eq!(f5.depth_true, g5.depth_true);
    assert_eq!(f5.pose_wc, g5.pose_wc);
    assert_eq!(f5.timestamp, g5.timestamp);
    let other = Generator::new(cfg, 10).frame(5);
    assert_ne!(f5.rgb, other.rgb);
    assert_ne!(f5.depth, other.depth);
}

/// Minimal FAST-9 without suppression (slam-core's 16-pixel circle of radius 3, 9 contiguous
/// brighter or darker by `t`): every corner pixel, to measure texture richness.
fn fast9(img: &[u8], w: usize, h: usize, t: i16) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for y in 3..h.saturating_sub(3) {
        for x in 3..w.saturating_sub(3) {
            let p = img[y * w + x] as i16;
            let s: Vec<i8> = CIRCLE
                .iter()
                .map(|&(dx, dy)| {
                    let q = img
                        [(y as i64 + dy as i64) as usize * w + (x as i64 + dx as i64) as usize]
                        as i16;
                    if q > p + t {
                        1
                    } else if q < p - t {
                        -1
                    } else {
                        0
                    }
                })
                .collect();
            let corner = [1i8, -1].iter().any(|&sign| {
                let mut run = 0;
                (0..32).any(|k| {
                    run = if s[k % 16] == sign { run + 1 } else { 0 };
                    run >= 9
                })
            });
            if corner {
                out.push((x, y));
            }
        }
    }
    out
}

fn downscale(img: &[u8], w: usize, h: usize, f: f64) -> (Vec<u8>, usize, usize) {
    let (nw, nh) = ((w as f64 / f) as usize, (h as f64 / f) as usize);
    let mut out = vec![0u8; nw * nh];
    for y in 0..nh {
        for x in 0..nw {
            let (sx, sy) = (
                ((x as f64 + 0.5) * f) as usize,
                ((y as f64 + 0.5) * f) as usize,
            );
            out[y * nw + x] = img[sy.min(h - 1) * w + sx.min(w - 1)];
        }
    }
    (out, nw, nh)
}

/// The textures give FAST (threshold 20) thousands of corners over an 8-level 1.2 pyramid,
/// spread over the whole image, on every trajectory.
#[test]
fn images_have_many_well_spread_fast_corners() {
    for (preset, traj) in [
        ("kinect", synth::Trajectory::Xyz),
        ("kinect", synth::Trajectory::Spin),
        ("kinect", synth::Trajectory::Rpy),
        ("stereo", synth::Trajectory::Xyz),
        ("loop", synth::Trajectory::Loop),
    ] {
        let mut cfg = SynthConfig::preset(preset).unwrap();
        cfg.trajectory = traj.clone();
        let gen = Generator::new(cfg, 4);
        for i in [0usize, 150] {
            let f = gen.frame(i);
            let (w, h) = (f.gray.width, f.gray.height);
            let level0 = fast9(&f.gray.data, w, h, 20);
            // Spread: 8 x 6 cells, nearly all with corners.
            let mut cells = [0usize; 48];
            for &(x, y) in &level0 {
                cells[(y * 6 / h) * 8 + x * 8 / w] += 1;
            }
            let covered = cells.iter().filter(|&&c| c >= 5).count();
            let mut total = level0.len();
            let (mut img, mut lw, mut lh) = (f.gray.data.clone(), w, h);
            for _ in 1..8 {
                let (d, nw, nh) = downscale(&img, lw, lh, 1.2);
                total += fast9(&d, nw, nh, 20).len();
                (img, lw, lh) = (d, nw, nh);
            }
            assert!(total > 3000, "{preset} {traj:?} frame {i}: {total} corners");
            assert!(
                covered >= 44,
                "{preset} {traj:?} frame {i}: {covered}/48 cells"
            );
        }
    }
}

/// The walking people cover 20-40 % of the view on average, and a good part for most frames.
#[test]
fn walking_people_cover_a_fifth_to_two_fifths_of_the_view() {
    let gen = Generator::new(SynthConfig::preset("walking").unwrap(), 1);
    let cov: Vec<f64> = (0..600)
        .step_by(20)
        .map(|i| {
            let m = gen.frame(i).moving_mask.unwrap();
            m.iter().filter(|&&b| b).count() as f64 / m.len() as f64
        })
        .collect();
    let mean = cov.iter().sum::<f64>() / cov.len() as f64;
    let often = cov.iter().filter(|&&c| c > 0.1).count() as f64 / cov.len() as f64;
    assert!((0.2..=0.4).contains(&mean), "mean coverage {mean}: {cov:?}");
    assert!(often > 0.6, "people visible in only {often} of frames");
}

/// The occlusion window covers the lens with a flat featureless surface.
#[test]
fn occlusion_window_is_flat_and_featureless() {
    let mut cfg = SynthConfig::preset("kinect").unwrap();
    cfg.occlusion = Some((10, 5));
    let gen = Generator::new(cfg, 1);
    let inside = gen.frame(12);
    let d = inside.depth_true.unwrap();
    assert!(d.data.iter().all(|&z| z == 0.5));
    let (w, h) = (inside.gray.width, inside.gray.height);
    assert!(fast9(&inside.gray.data, w, h, 20).len() < 20);
    let outside = gen.frame(15);
    assert!(fast9(&outside.gray.data, w, h, 20).len() > 1000);
}

/// Depth lag: the measured depth of frame i is the scene seen 2 frames earlier.
#[test]
fn depth_lag_renders_depth_from_the_earlier_pose() {
    let mut cfg = clean_with(DepthNoise {
        lag: Some(DepthLag { frames: 2.0 }),
        ..DepthNoise::default()
    });
    cfg.moving_objects = Some(MovingObjects::default());
    let gen = Generator::new(cfg, 1);
    let now = gen.frame(30);
    let before = gen.frame(28);
    let m = now.depth.unwrap();
    let (tb, tn) = (before.depth_true.unwrap(), now.depth_true.unwrap());
    let close = |a: &[f32], b: &[f32]| {
        a.iter()
            .zip(b)
            .filter(|(x, y)| (**x - **y).abs() < 1e-3)
            .count()
    };
    let n = m.data.len();
    assert!(close(&m.data, &tb.data) as f64 > 0.99 * n as f64);
    assert!((close(&m.data, &tn.data) as f64) < 0.9 * n as f64);
}

/// Systematic distortion: the depth scale error shows at the image centre.
#[test]
fn systematic_distortion_scales_depth() {
    let gen = Generator::new(
        clean_with(DepthNoise {
            distortion: Some(SystematicDistortion::default()),
            ..DepthNoise::default()
        }),
        1,
    );
    let f = gen.frame(0);
    let (m, t) = (f.depth.unwrap(), f.depth_true.unwrap());
    let i = 240 * m.width + 320;
    let ratio = m.data[i] / t.data[i];
    assert!((ratio - 1.04).abs() < 0.002, "ratio {ratio}");
}

/// Stereo: the right image is the left one shifted by the disparity bf / z.
#[test]
fn stereo_right_image_matches_disparity() {
    let gen = Generator::new(SynthConfig::preset("stereo").unwrap(), 1);
    let cam = gen.camera();
    let f = gen.frame(10);
    let (l, r, d) = (
        &f.gray,
        f.right.as_ref().unwrap(),
        f.depth_true.as_ref().unwrap(),
    );
    assert!(f.depth.is_none() && f.rgb.is_none());
    let (mut shifted, mut unshifted, mut n) = (0.0, 0.0, 0);
    for v in (10..l.height - 10).step_by(3) {
        for u in (120..l.width - 10).step_by(3) {
            let z = d.get(u, v).unwrap() as f64;
            let ur = (u as f64 - cam.bf / z).round() as usize;
            shifted += (l.get(u, v) as f64 - r.get(ur, v) as f64).abs();
            unshifted += (l.get(u, v) as f64 - r.get(u, v) as f64).abs();
            n += 1;
        }
    }
    let (s, un) = (shifted / n as f64, unshifted / n as f64);
    assert!(s < 0.5 * un && s < 12.0, "shifted {s}, unshifted {un}");
}
