//! The systematic families and named camera chains, each measured on its own output against
//! its definition: depth on walls and steps, the given camera, the scored ground truth.

use ate_eval::{evaluate_ate, AteOptions, Trajectory};
use datasets::{Format, FrameReader, Sequence};
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use perturb::{perturb_sequence, Chain, Family, NamedChain};
use slam_core::{Camera, DepthImage, FrameInput, GrayImage, SensorKind};
use std::sync::Arc;

const UNITS: f64 = 5000.0;

fn q(z: f64) -> f32 {
    ((z * UNITS).round() / UNITS) as f32
}

fn frame(w: usize, h: usize, t: f64, depth: impl Fn(usize, usize) -> f64) -> FrameInput {
    FrameInput {
        timestamp: t,
        image: Arc::new(GrayImage {
            width: w,
            height: h,
            data: (0..w * h)
                .map(|i| ((i * 7 + i / w * 13) % 256) as u8)
                .collect(),
        }),
        depth: Some(Arc::new(DepthImage {
            width: w,
            height: h,
            data: (0..w * h).map(|i| q(depth(i % w, i / w))).collect(),
        })),
        right: None,
        colour: None,
    }
}

/// A ground truth moving along x at 0.4 m/s with a slow turn, 100 Hz.
fn groundtruth(n: usize) -> Trajectory {
    Trajectory {
        stamps: (0..n).map(|i| i as f64 * 0.01).collect(),
        poses: (0..n)
            .map(|i| {
                let t = i as f64 * 0.01;
                Isometry3::from_parts(
                    Vector3::new(0.4 * t, 0.1 * (3.0 * t).sin(), 0.05 * t * t).into(),
                    UnitQuaternion::from_euler_angles(0.0, 0.3 * t, 0.1 * t),
                )
            })
            .collect(),
    }
}

fn sequence(
    camera: Camera,
    n: usize,
    depth: impl Fn(usize, usize, usize) -> f64 + Send + Sync + 'static,
) -> (Sequence, FrameReader) {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let seq = Sequence {
        name: "test".into(),
        camera,
        frames: vec![],
        groundtruth: Some(groundtruth(300)),
        t_bs: None,
        format: Format::TumRgbd,
        notes: vec![],
        depth_factor: Some(UNITS),
        rectification: None,
    };
    let reader = FrameReader::new(n, move |i| {
        Ok(frame(w, h, i as f64 / 30.0, |x, y| depth(i, x, y)))
    });
    (seq, reader)
}

fn apply(s: &(Sequence, FrameReader), chain: &str, seed: u64) -> (Sequence, FrameReader) {
    perturb_sequence(&s.0, s.1.clone(), &Chain::parse(chain).unwrap(), seed).unwrap()
}

fn depth_of(r: &FrameReader, i: usize) -> Vec<f32> {
    r.read(i).unwrap().depth.unwrap().data.clone()
}

#[test]
fn disparity_quantization_steps_grow_as_z_squared_over_8fb() {
    // A ramp in depth along x, so many lattice values are hit; the distinct output depths near
    // 1 m and 2 m are Z^2 / (8 f b) apart (f b = 43.5 px m): 2.87 mm and 11.5 mm.
    for (z0, level) in [(1.0, 1.0), (2.0, 1.0), (1.0, 2.0)] {
        let s = sequence(Camera::tum_fr3(), 1, move |_, x, _| {
            z0 - 0.05 + 0.1 * x as f64 / 640.0
        });
        let (_, r) = apply(&s, &format!("disparity-quantization:{level}"), 1);
        let mut v: Vec<f32> = depth_of(&r, 0);
        v.sort_by(f32::total_cmp);
        v.dedup();
        let gaps: Vec<f64> = v
            .windows(2)
            .filter(|p| (p[0] as f64 - z0).abs() < 0.03)
            .map(|p| (p[1] - p[0]) as f64)
            .collect();
        let gap = gaps.iter().sum::<f64>() / gaps.len() as f64;
        let want = level * z0 * z0 / (8.0 * 43.5);
        assert!(
            (gap / want - 1.0).abs() < 0.10,
            "{z0} m, level {level}: step {gap} vs {want}"
        );
    }
}

#[test]
fn disparity_quantization_jitters_before_rounding() {
    // A wall between two lattice values: the jitter (half a step, sigma) sends pixels to both.
    let (_, r) = apply(
        &sequence(Camera::tum_fr3(), 1, |_, _, _| 1.0),
        "disparity-quantization:1",
        3,
    );
    let mut v = depth_of(&r, 0);
    v.sort_by(f32::total_cmp);
    v.dedup();
    assert!(v.len() >= 2 && v.len() <= 5, "{v:?}");
}

#[test]
fn depth_distortion_is_fixed_grows_with_range_and_peaks_at_the_level_at_3m() {
    let level = 2.0;
    let rel = |z: f64, frame: usize| -> Vec<f64> {
        let s = sequence(Camera::tum_fr3(), 2, move |_, _, _| z);
        let (_, r) = apply(&s, &format!("depth-distortion:{level}"), 9);
        depth_of(&r, frame)
            .iter()
            .map(|&d| d as f64 / q(z) as f64 - 1.0)
            .collect()
    };
    let at3 = rel(3.0, 0);
    let peak = at3.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    assert!((peak * 100.0 - level).abs() < 0.01, "{peak}");
    // The same field in every frame.
    assert_eq!(at3, rel(3.0, 1));
    // Half the relative error at 1.5 m, pixel by pixel (to the PNG grid).
    let at15 = rel(1.5, 0);
    for (a, b) in at3.iter().zip(&at15).step_by(97) {
        assert!((b - a / 2.0).abs() < 2.0e-4, "{a} {b}");
    }
    // Smooth: neighbouring pixels differ by far less than the peak.
    let step = at3
        .chunks(640)
        .flat_map(|row| row.windows(2).map(|p| (p[1] - p[0]).abs()))
        .fold(0.0, f64::max);
    assert!(step < 0.05 * peak + 1e-4, "{step}");
}

#[test]
fn depth_registration_warps_by_its_level_and_fattens_foreground() {
    // Depth that says where it was read: one PNG unit (0.2 mm) per column, then per row.
    let by_x = sequence(Camera::tum_fr3(), 2, |_, x, _| 0.5 + x as f64 / UNITS);
    let by_y = sequence(Camera::tum_fr3(), 1, |_, _, y| 0.5 + y as f64 / UNITS);
    let r = apply(&by_x, "depth-registration:3", 4).1;
    let d = depth_of(&r, 0);
    let dy = depth_of(&apply(&by_y, "depth-registration:3", 4).1, 0);
    let mut n = 0;
    for y in (20..460).step_by(37) {
        for x in (20..620).step_by(41) {
            let sx = ((d[y * 640 + x] as f64 - 0.5) * UNITS).round();
            let sy = ((dy[y * 640 + x] as f64 - 0.5) * UNITS).round();
            let moved = ((sx - x as f64).powi(2) + (sy - y as f64).powi(2)).sqrt();
            assert!(
                (moved - 3.0).abs() <= 0.75,
                "({x}, {y}) read at ({sx}, {sy})"
            );
            n += 1;
        }
    }
    assert!(n > 100);
    assert_eq!(d, depth_of(&r, 1), "the warp is fixed for the sequence");
    // A foreground square on a far wall: after the warp it is never smaller, and it has grown.
    let s = sequence(Camera::tum_fr3(), 1, |_, x, y| {
        if (200..400).contains(&x) && (150..300).contains(&y) {
            1.0
        } else {
            3.0
        }
    });
    let count = |r: &FrameReader| depth_of(r, 0).iter().filter(|&&z| z < 2.0).count();
    let before = count(&s.1);
    let after = count(&apply(&s, "depth-registration:4", 4).1);
    assert!(after > before + 150, "{before} -> {after}");
}

#[test]
fn ir_shadow_holes_lie_left_of_left_edges_with_the_formula_width() {
    // A near slab (1 m) from column 300 to 400 on a far wall (2.5 m).
    let (zf, zb) = (1.0, 2.5);
    let s = sequence(Camera::tum_fr3(), 1, move |_, x, _| {
        if (300..400).contains(&x) {
            zf
        } else {
            zb
        }
    });
    for level in [1.0, 2.0] {
        let (_, r) = apply(&s, &format!("ir-shadow:{level}"), 0);
        let d = depth_of(&r, 0);
        let fb = Camera::tum_fr3().fx * 0.075 * level;
        let want = fb * (1.0 / zf - 1.0 / zb);
        for y in [0usize, 240, 479] {
            let row = &d[y * 640..(y + 1) * 640];
            let holes: Vec<usize> = (0..640).filter(|&x| row[x] == 0.0).collect();
            // Only left of the slab's left edge, contiguous up to it.
            assert!(holes.iter().all(|&x| x < 300), "level {level}: {holes:?}");
            assert_eq!(*holes.last().unwrap(), 299);
            let width = holes.len() as f64;
            assert!(
                (width - want).abs() <= 1.0,
                "level {level}: {width} vs {want}"
            );
        }
        // The slab and the right side keep their depth.
        assert!((300..640).all(|x| d[240 * 640 + x] > 0.0));
    }
}

#[test]
fn calibration_families_change_the_given_camera_and_no_pixel() {
    let s = sequence(Camera::tum_fr1(), 2, |_, x, _| 1.0 + x as f64 * 0.001);
    let (seq, r) = apply(&s, "focal-error:1", 0);
    assert!((seq.camera.fx / s.0.camera.fx - 1.01).abs() < 1e-12);
    assert!((seq.camera.fy / s.0.camera.fy - 1.01).abs() < 1e-12);
    for i in 0..2 {
        let (a, b) = (r.read(i).unwrap(), s.1.read(i).unwrap());
        assert_eq!(a.image.data, b.image.data);
        assert_eq!(a.depth.unwrap().data, b.depth.unwrap().data);
    }
    let (seq, _) = apply(&s, "principal-point-error:2+distortion-error:0.5", 0);
    let moved = (seq.camera.cx - s.0.camera.cx).hypot(seq.camera.cy - s.0.camera.cy);
    assert!((moved - 2.0).abs() < 1e-9);
    let (k, k0) = (
        seq.camera.distortion.unwrap().k1,
        s.0.camera.distortion.unwrap().k1,
    );
    assert!((k - 0.5 * k0).abs() < 1e-15);
    // A camera without distortion has none to leave out.
    let fr3 = sequence(Camera::tum_fr3(), 1, |_, _, _| 1.0);
    let e = perturb_sequence(
        &fr3.0,
        fr3.1.clone(),
        &Chain::parse("distortion-error:0.5").unwrap(),
        0,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("distortion-error does not apply to test"), "{e}");
}

/// An estimate: the ground truth sampled at 30 Hz with a small wobble, so the ATE is not 0.
fn estimate(gt: &Trajectory) -> Trajectory {
    let mut est = Trajectory::default();
    for k in 0..90 {
        let t = 0.02 + k as f64 / 30.0;
        let i = (t / 0.01).round() as usize;
        let mut p = gt.poses[i];
        p.translation.vector.y += 0.002 * (k as f64).sin();
        est.stamps.push(t);
        est.poses.push(p);
    }
    est
}

#[test]
fn gt_offset_scores_as_eval_offset_does() {
    let s = sequence(Camera::tum_fr3(), 1, |_, _, _| 1.0);
    let est = estimate(s.0.groundtruth.as_ref().unwrap());
    let (seq, r) = apply(&s, "gt-offset:10", 0);
    // The frames are not touched.
    assert_eq!(depth_of(&r, 0), depth_of(&s.1, 0));
    let perturbed = evaluate_ate(
        seq.groundtruth.as_ref().unwrap(),
        &est,
        &AteOptions::default(),
    )
    .unwrap();
    let offset = evaluate_ate(
        s.0.groundtruth.as_ref().unwrap(),
        &est,
        &AteOptions {
            offset: 0.010,
            ..AteOptions::default()
        },
    )
    .unwrap();
    let clean = evaluate_ate(
        s.0.groundtruth.as_ref().unwrap(),
        &est,
        &AteOptions::default(),
    )
    .unwrap();
    assert_eq!(perturbed.pairs, offset.pairs);
    assert!((perturbed.stats.rmse - offset.stats.rmse).abs() < 1e-9);
    // 10 ms at 0.4 m/s is 4 mm along the path; the alignment absorbs its constant part.
    assert!(
        perturbed.stats.rmse > clean.stats.rmse + 0.0005,
        "{} vs {}",
        perturbed.stats.rmse,
        clean.stats.rmse
    );
}

#[test]
fn gt_families_need_a_ground_truth() {
    let mut s = sequence(Camera::tum_fr3(), 1, |_, _, _| 1.0);
    s.0.groundtruth = None;
    for chain in ["gt-jitter:1", "kinect-fr3:1"] {
        let e = perturb_sequence(&s.0, s.1.clone(), &Chain::parse(chain).unwrap(), 0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("has no ground truth"), "{chain}: {e}");
    }
}

#[test]
fn level_zero_of_every_family_and_chain_is_the_input() {
    let s = sequence(Camera::tum_fr1(), 2, |_, x, y| {
        1.0 + (x * y % 97) as f64 * 0.01
    });
    let names: Vec<&str> = Family::ALL
        .iter()
        .filter(|f| f.applies_to(SensorKind::Rgbd))
        .map(|f| f.name())
        .chain(
            NamedChain::ALL
                .iter()
                .filter(|c| {
                    c.members()
                        .iter()
                        .all(|m| m.family.applies_to(SensorKind::Rgbd))
                })
                .map(|c| c.name()),
        )
        .collect();
    for name in names {
        let level = if name == "frame-drop" { 1 } else { 0 };
        let (seq, r) = apply(&s, &format!("{name}:{level}"), 5);
        assert_eq!(seq.camera, s.0.camera, "{name}");
        assert_eq!(seq.groundtruth, s.0.groundtruth, "{name}");
        for i in 0..2 {
            let (a, b) = (r.read(i).unwrap(), s.1.read(i).unwrap());
            assert_eq!(a.image.data, b.image.data, "{name}");
            assert_eq!(a.depth.unwrap().data, b.depth.unwrap().data, "{name}");
            assert_eq!(a.timestamp.to_bits(), b.timestamp.to_bits(), "{name}");
        }
    }
}

#[test]
fn named_chains_expand_multiply_and_refuse_bad_input() {
    let one = Chain::parse("kinect-fr1:1").unwrap();
    let members = NamedChain::KinectFr1.members();
    assert_eq!(one.0.len(), members.len());
    let two = Chain::parse("kinect-fr1:2").unwrap();
    for ((a, b), m) in one.0.iter().zip(&two.0).zip(members) {
        assert_eq!((a.family, b.family), (m.family, m.family));
        assert!((b.level - 2.0 * a.level).abs() < 1e-8);
    }
    // Spelled out, it reads back to itself.
    assert_eq!(Chain::parse(&one.to_string()).unwrap(), one);
    // A chain combines with families.
    assert_eq!(
        Chain::parse("kinect-fr2:1+depth-axial:2").unwrap().0.len(),
        10
    );
    let e = Chain::parse("kinect-fr9:1").unwrap_err().to_string();
    assert!(
        e.contains("kinect-fr9") && e.contains("kinect-fr1") && e.contains("depth-axial"),
        "{e}"
    );
    let e = Chain::parse("kinect-fr1:100").unwrap_err().to_string();
    assert!(e.contains("kinect-fr1:100") && e.contains("0 to"), "{e}");
    let e = Chain::parse("focal-error:30").unwrap_err().to_string();
    assert!(e.contains("-20 to 20"), "{e}");
    let axis = perturb::Axis::parse("kinect-fr1:0,0.5,1,2,4").unwrap();
    assert_eq!(axis.levels, vec![0.0, 0.5, 1.0, 2.0, 4.0]);
    assert!(axis.subject.is_identity(0.0) && !axis.subject.is_identity(0.5));
    // The stereo chain refuses an RGB-D sequence, the RGB-D chains a stereo one.
    assert!(Chain::parse("kinect-fr3:1")
        .unwrap()
        .check_sensor(SensorKind::Stereo, "s")
        .is_err());
    assert!(Chain::parse("euroc:1")
        .unwrap()
        .check_sensor(SensorKind::Rgbd, "s")
        .is_err());
}

#[test]
fn a_chain_at_one_moves_depth_camera_and_truth_together() {
    let s = sequence(Camera::tum_fr1(), 2, |_, x, _| {
        if (300..400).contains(&x) {
            1.0
        } else {
            2.5
        }
    });
    let (seq, r) = apply(&s, "kinect-fr1:1", 2);
    assert!((seq.camera.fx / s.0.camera.fx - 1.005).abs() < 1e-12);
    assert_ne!(seq.groundtruth, s.0.groundtruth);
    let d = depth_of(&r, 0);
    // Shadow holes left of the slab, depth read about 3.4 % short on the far wall's middle.
    assert!((250..300).any(|x| d[240 * 640 + x] == 0.0));
    let far = d[240 * 640 + 600] as f64;
    assert!((far / 2.5 - 1.0 + 0.0338).abs() < 0.02, "{far}");
}

#[test]
fn an_ablation_has_the_chain_each_member_alone_and_the_chain_without_each() {
    let axes = perturb::ablation_axes(NamedChain::KinectFr2, 1.0);
    let members = NamedChain::KinectFr2.members();
    assert_eq!(axes.len(), 1 + 2 * members.len());
    assert_eq!(axes[0].subject.name(), "kinect-fr2");
    for (k, m) in members.iter().enumerate() {
        let alone = &axes[1 + k];
        assert_eq!(alone.subject.name(), m.family.name());
        assert_eq!(alone.levels, vec![0.0, m.level]);
        let without = &axes[1 + members.len() + k];
        assert_eq!(without.subject.name(), format!("kinect-fr2~{}", m.family));
        let applied = without.subject.at(1.0);
        assert_eq!(applied.len(), members.len() - 1);
        assert!(applied.iter().all(|p| p.family != m.family));
        // The spelling reads back to the same axis.
        let text = format!("{}:0,1", without.subject);
        assert_eq!(&perturb::Axis::parse(&text).unwrap(), without);
    }
    let e = Chain::parse("kinect-fr3~distortion-error:1")
        .unwrap_err()
        .to_string();
    assert!(e.contains("a member of kinect-fr3"), "{e}");
}

/// A frame with colour: a different pattern per channel, the grey its luma.
fn coloured(s: &(Sequence, FrameReader)) -> (Sequence, FrameReader) {
    let inner = s.1.clone();
    let reader = FrameReader::new(inner.len(), move |i| {
        let mut f = inner.read(i)?;
        let (w, h) = (f.image.width, f.image.height);
        let data: Vec<u8> = (0..w * h)
            .flat_map(|p| {
                let (x, y) = (p % w, p / w);
                [
                    ((x * 3 + y) % 256) as u8,
                    ((x + 5 * y) % 200 + 20) as u8,
                    ((x * y) % 97 + 100) as u8,
                ]
            })
            .collect();
        let c = slam_core::ColourImage {
            width: w,
            height: h,
            data,
        };
        f.image = Arc::new(c.to_gray());
        f.colour = Some(Arc::new(c));
        Ok(f)
    });
    (s.0.clone(), reader)
}

#[test]
fn colour_stays_colour_and_level_zero_keeps_every_colour_byte() {
    let s = coloured(&sequence(Camera::tum_fr1(), 2, |_, x, _| {
        1.0 + x as f64 * 0.001
    }));
    let names: Vec<&str> = Family::ALL
        .iter()
        .filter(|f| f.applies_to(SensorKind::Rgbd))
        .map(|f| f.name())
        .collect();
    for name in names {
        let level = if name == "frame-drop" { 1 } else { 0 };
        let (_, r) = apply(&s, &format!("{name}:{level}"), 5);
        let (a, b) = (r.read(1).unwrap(), s.1.read(1).unwrap());
        assert_eq!(a.colour.unwrap().data, b.colour.unwrap().data, "{name}");
    }
    // Depth, calibration and ground-truth families leave the colour as it is.
    let (_, r) = apply(&s, "kinect-fr1:1", 5);
    assert_eq!(
        r.read(0).unwrap().colour.unwrap().data,
        s.1.read(0).unwrap().colour.unwrap().data
    );
    // The image families act on the colour; the grey is its luma.
    for chain in [
        "image-noise:6",
        "motion-blur:5",
        "exposure:20",
        "jpeg:30",
        "occluders:2",
    ] {
        let (_, r) = apply(&s, chain, 5);
        let f = r.read(1).unwrap();
        let c = f.colour.clone().unwrap();
        assert_eq!(f.image.data, c.to_gray().data, "{chain}");
        assert_ne!(c.data, s.1.read(1).unwrap().colour.unwrap().data, "{chain}");
    }
    // Noise is drawn per channel: a grey-constant patch gets three different noises.
    let (_, r) = apply(&s, "image-noise:8", 1);
    let c = r.read(0).unwrap().colour.unwrap();
    let clean = s.1.read(0).unwrap().colour.unwrap();
    let diff = |k: usize| -> Vec<i32> {
        (0..2000)
            .map(|p| c.data[3 * p + k] as i32 - clean.data[3 * p + k] as i32)
            .collect()
    };
    assert_ne!(diff(0), diff(1));
    assert_ne!(diff(1), diff(2));
    // Occluders draw grey textures: drawn pixels are (g, g, g).
    let (_, r) = apply(&s, "occluders:3", 2);
    let (f, clean) = (r.read(0).unwrap(), s.1.read(0).unwrap());
    let c = f.colour.unwrap();
    let drawn: Vec<usize> = (0..f.image.data.len())
        .filter(|&p| {
            c.data[3 * p..3 * p + 3] != clean.colour.as_ref().unwrap().data[3 * p..3 * p + 3]
        })
        .collect();
    assert!(!drawn.is_empty());
    assert!(drawn
        .iter()
        .all(|&p| c.data[3 * p] == c.data[3 * p + 1] && c.data[3 * p + 1] == c.data[3 * p + 2]));
}

/// A recorded chain's members are recognised as the named chain at its level.
#[test]
fn a_chain_spelled_by_its_members_is_recognised_with_its_level() {
    for c in NamedChain::ALL {
        for level in [0.5, 1.0, 2.0, 5.0] {
            let spelled = Chain(c.at(level)).effective().to_string();
            let parsed = Chain::parse(&spelled).unwrap();
            assert_eq!(parsed.named(), Some((c, level)), "{spelled}");
        }
    }
    // One member changed, or one left out: not the chain.
    let mut members = NamedChain::KinectFr1.at(2.0);
    members[0].level *= 1.5;
    assert_eq!(Chain(members.clone()).named(), None);
    assert_eq!(Chain(members[1..].to_vec()).named(), None);
    assert_eq!(Chain::parse("depth-axial:4").unwrap().named(), None);
}
