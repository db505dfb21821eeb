//! The recording's clocks against their definitions: stream stamps off their capture instants
//! by the configured jitter (colour and a free-running depth stream independently, a
//! synchronised depth stream with the colour's stamp), the motion-capture clock's samples on
//! their own grid and phase, and neither touching the images.

use synth::motion::clock::T0_NS;
use synth::{DepthLag, Generator, SynthConfig};
use synth::{MocapClock, StreamStamps};

const FPS: f64 = 30.0;

/// `kinect` with a depth lag of a third of a frame and the given clocks.
fn kinect(stamps: Option<StreamStamps>, mocap_clock: Option<MocapClock>) -> SynthConfig {
    let mut c = SynthConfig::preset("kinect").unwrap();
    c.depth_noise.lag = Some(DepthLag { frames: 1.0 / 3.0 });
    c.stamps = stamps;
    c.mocap_clock = mocap_clock;
    c.validate().unwrap();
    c
}

/// Seconds since frame 0 of a stamp in nanoseconds since the epoch.
fn since_t0(ns: u64) -> f64 {
    (ns as i128 - T0_NS as i128) as f64 * 1e-9
}

fn mean_sd(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    (
        m,
        (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n).sqrt(),
    )
}

#[test]
fn stream_stamps_jitter_about_each_streams_capture_instant() {
    let (sd_rgb, sd_depth) = (0.0015, 0.001);
    let gen = Generator::new(
        kinect(
            Some(StreamStamps {
                rgb_jitter_s: sd_rgb,
                depth_jitter_s: Some(sd_depth),
            }),
            None,
        ),
        3,
    );
    let n = 4000;
    let lag = 1.0 / 3.0 / FPS;
    let e_rgb: Vec<f64> = (0..n)
        .map(|i| since_t0(gen.stamp_ns(i)) - gen.time(i))
        .collect();
    let e_depth: Vec<f64> = (0..n)
        .map(|i| since_t0(gen.depth_stamp_ns(i)) - (gen.time(i) - lag))
        .collect();
    for (e, sd) in [(&e_rgb, sd_rgb), (&e_depth, sd_depth)] {
        let (m, s) = mean_sd(e);
        assert!(m.abs() < 0.1 * sd, "mean {m}");
        assert!((s / sd - 1.0).abs() < 0.05, "sd {s} against {sd}");
        // Clipped at 4 sigma, rounded to the microsecond.
        assert!(e.iter().all(|v| v.abs() <= 4.0 * sd + 1.1e-6));
    }
    // The two streams' jitters are independent.
    let (mr, sr) = mean_sd(&e_rgb);
    let (md, sdd) = mean_sd(&e_depth);
    let cov = (0..n)
        .map(|i| (e_rgb[i] - mr) * (e_depth[i] - md))
        .sum::<f64>()
        / n as f64;
    assert!(
        (cov / (sr * sdd)).abs() < 0.05,
        "correlation {}",
        cov / (sr * sdd)
    );
    // Intervals of white stamp noise spread sqrt(2) sigma; both streams stay in order; stamps
    // are whole microseconds (TUM's 6 decimals).
    let intervals: Vec<f64> = (1..n)
        .map(|i| since_t0(gen.stamp_ns(i)) - since_t0(gen.stamp_ns(i - 1)))
        .collect();
    let (mi, si) = mean_sd(&intervals);
    assert!((mi - 1.0 / FPS).abs() < 1e-5, "{mi}");
    assert!((si / (sd_rgb * 2f64.sqrt()) - 1.0).abs() < 0.06, "{si}");
    for i in 1..n {
        assert!(gen.stamp_ns(i) > gen.stamp_ns(i - 1));
        assert!(gen.depth_stamp_ns(i) > gen.depth_stamp_ns(i - 1));
        assert_eq!(gen.stamp_ns(i) % 1000, 0);
        assert_eq!(gen.depth_stamp_ns(i) % 1000, 0);
        assert!((gen.timestamp(i) - gen.stamp_ns(i) as f64 * 1e-9).abs() < 1e-6);
    }
    // Random access: the same stamp however often and in whatever order it is asked for.
    assert_eq!(
        gen.stamp_ns(1234),
        Generator::new(gen.config().clone(), 3).stamp_ns(1234)
    );
    assert_ne!(
        gen.stamp_ns(1234),
        Generator::new(gen.config().clone(), 4).stamp_ns(1234)
    );
}

#[test]
fn a_synchronised_depth_stream_carries_the_colour_stamp_and_no_effect_keeps_exact_stamps() {
    let synced = Generator::new(
        kinect(
            Some(StreamStamps {
                rgb_jitter_s: 0.0015,
                depth_jitter_s: None,
            }),
            None,
        ),
        3,
    );
    let exact = Generator::new(kinect(None, None), 3);
    let mut moved = 0;
    for i in 0..300 {
        assert_eq!(synced.depth_stamp_ns(i), synced.stamp_ns(i));
        // Without the effect: the exact capture instant on both streams, a depth lag
        // notwithstanding (the sensor lies about its depth's time).
        let capture = T0_NS + (i as f64 * 1e9 / FPS).round() as u64;
        let capture = (capture + 500) / 1000 * 1000;
        assert_eq!(exact.stamp_ns(i), capture);
        assert_eq!(exact.depth_stamp_ns(i), capture);
        assert!((since_t0(capture) - exact.time(i)).abs() < 1e-12);
        // The jitter moves stamps, never the capture instant.
        assert_eq!(synced.time(i), exact.time(i));
        moved += usize::from(synced.stamp_ns(i) != capture);
    }
    assert!(moved > 290, "{moved}");
}

#[test]
fn mocap_clock_samples_the_path_on_its_own_grid() {
    let rate = 100.0;
    let n = 95;
    let clock = Some(MocapClock { rate_hz: rate });
    let gen = Generator::new(kinect(None, clock), 7);
    let gt = gen.groundtruth(n);
    let t0 = T0_NS as f64 * 1e-9;
    let (first, last) = (t0 + gen.time(0), t0 + gen.time(n - 1));
    // From the last sample at or before frame 0 to the first at or after frame n - 1.
    assert!(gt[0].0 <= first + 1e-6 && gt[1].0 > first);
    assert!(gt[gt.len() - 1].0 >= last - 1e-6 && gt[gt.len() - 2].0 < last);
    for w in gt.windows(2) {
        // One period apart, up to the 0.1 ms rounding of the stamps.
        assert!(((w[1].0 - w[0].0) - 1.0 / rate).abs() < 1.0e-4 + 1e-6);
    }
    for (t, pose) in &gt {
        // Stamps on TUM's 0.1 ms resolution; the pose is the path's at the stamp (no noise
        // configured; the stamp in seconds since the epoch holds 0.2 microseconds).
        let tenths = (t - t0) * 1e4;
        assert!((tenths - tenths.round()).abs() < 1e-2, "{t}");
        let truth = gen.pose_at_time(t - t0);
        assert!((pose.translation.vector - truth.translation.vector).norm() < 1e-6);
        assert!(pose.rotation.angle_to(&truth.rotation) < 1e-6);
    }
    // Every frame has a sample within half a period, and the frames do not sit on the grid.
    let nearest = |s: f64| {
        gt.iter()
            .map(|(t, _)| (t - s).abs())
            .fold(f64::INFINITY, f64::min)
    };
    let offsets: Vec<f64> = (0..n).map(|i| nearest(t0 + gen.time(i))).collect();
    assert!(offsets.iter().all(|&d| d <= 0.5 / rate + 1e-4));
    assert!(offsets.iter().filter(|&&d| d > 1e-3).count() > n / 2);
    // The phase comes from the seed: other seeds, other grids; the same seed, the same one.
    let phase = |seed| {
        let g = Generator::new(kinect(None, clock), seed).groundtruth(2);
        ((g[0].0 - t0) * 1e4).round() as i64
    };
    let phases: Vec<i64> = (0..6).map(phase).collect();
    assert!(phases.windows(2).any(|w| w[0] != w[1]), "{phases:?}");
    assert_eq!(phase(7), phase(7));
    // Without the clock: one pose per frame at its capture instant.
    let plain = Generator::new(kinect(None, None), 7).groundtruth(n);
    assert_eq!(plain.len(), n);
    for (i, (t, pose)) in plain.iter().enumerate() {
        assert!((t - (t0 + gen.time(i))).abs() < 1e-6);
        assert_eq!(*pose, gen.pose(i));
    }
}

#[test]
fn mocap_noise_is_drawn_per_clock_sample() {
    let mut c = kinect(None, Some(MocapClock { rate_hz: 300.0 }));
    c.mocap_noise = Some(synth::MocapNoise {
        position_m: 0.001,
        angle_rad: 0.0,
    });
    let gen = Generator::new(c, 2);
    let gt = gen.groundtruth(300);
    let t0 = T0_NS as f64 * 1e-9;
    let errors: Vec<f64> = gt
        .iter()
        .flat_map(|(t, p)| {
            let d = p.translation.vector - gen.pose_at_time(t - t0).translation.vector;
            [d.x, d.y, d.z]
        })
        .collect();
    let (m, s) = mean_sd(&errors);
    assert!(gt.len() > 2900, "{}", gt.len());
    assert!(m.abs() < 1e-4 && (s / 0.001 - 1.0).abs() < 0.05, "{m} {s}");
}

#[test]
fn clocks_leave_the_images_alone_and_switch_off_by_name() {
    let stamps = StreamStamps {
        rgb_jitter_s: 0.0015,
        depth_jitter_s: Some(0.0015),
    };
    let clock = MocapClock { rate_hz: 100.0 };
    let with = kinect(Some(stamps), Some(clock));
    let without = kinect(None, None);
    let (a, b) = (
        Generator::new(with.clone(), 5),
        Generator::new(without.clone(), 5),
    );
    let (fa, fb) = (a.frame(2), b.frame(2));
    assert_eq!(fa.gray, fb.gray);
    assert_eq!(fa.depth, fb.depth);
    assert_eq!(fa.pose_wc, fb.pose_wc);
    assert_ne!(fa.timestamp, fb.timestamp);
    assert_eq!(fa.timestamp, a.timestamp(2));
    let mut off = with;
    off.without("stamp_jitter").unwrap();
    off.without("mocap_clock").unwrap();
    assert_eq!(off, without);
}

#[test]
fn clocks_are_refused_where_they_mean_nothing() {
    let stereo = |f: &dyn Fn(&mut SynthConfig)| {
        let mut c = SynthConfig::preset("stereo").unwrap();
        f(&mut c);
        c.validate().unwrap_err().to_string()
    };
    let e = stereo(&|c| {
        c.stamps = Some(StreamStamps {
            rgb_jitter_s: 0.001,
            depth_jitter_s: None,
        })
    });
    assert!(e.contains("RGB-D"), "{e}");
    let e = stereo(&|c| c.mocap_clock = Some(MocapClock { rate_hz: 100.0 }));
    assert!(e.contains("RGB-D"), "{e}");
    // A jitter that could reorder stamps, a rate out of range.
    let mut c = kinect(None, None);
    c.stamps = Some(StreamStamps {
        rgb_jitter_s: 0.004,
        depth_jitter_s: None,
    });
    assert!(c.validate().unwrap_err().to_string().contains("jitter"));
    c.stamps = None;
    c.mocap_clock = Some(MocapClock { rate_hz: 0.0 });
    assert!(c.validate().unwrap_err().to_string().contains("rate"));
}
