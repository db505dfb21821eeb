//! The project's ORB extractor (slam-core) finds its full budget of well-spread keypoints on
//! synthetic frames, and their descriptors match across consecutive frames consistently with
//! the ground-truth motion: the sequences are trackable.

use nalgebra::Point3;
use slam_core::feature::extractor::{OrbConfig, OrbExtractor};
use slam_core::feature::hamming;
use synth::{Generator, SynthConfig, Trajectory};

#[test]
fn orb_finds_1000_spread_keypoints_that_match_across_frames() {
    for (preset, traj) in [
        ("kinect", Trajectory::Xyz),
        ("walking", Trajectory::Rpy),
        ("kinect", Trajectory::Spin),
        ("loop", Trajectory::Loop),
    ] {
        let mut cfg = SynthConfig::preset(preset).unwrap();
        cfg.trajectory = traj.clone();
        let gen = Generator::new(cfg, 7);
        let cam = gen.camera();
        let mut orb = OrbExtractor::new(OrbConfig::default());
        let f0 = gen.frame(100);
        let f1 = gen.frame(101);
        let (k0, d0) = orb.extract(&f0.gray);
        let (k1, d1) = orb.extract(&f1.gray);
        let tag = format!("{preset} {traj:?}");
        assert!(
            k0.len() >= 950 && k1.len() >= 950,
            "{tag}: {} / {} keypoints",
            k0.len(),
            k1.len()
        );
        // Spread: keypoints in nearly all cells of an 8 x 6 grid.
        let mut cells = [0usize; 48];
        for k in &k0 {
            let (cx, cy) = (
                (k.x as usize * 8 / 640).min(7),
                (k.y as usize * 6 / 480).min(5),
            );
            cells[cy * 8 + cx] += 1;
        }
        let covered = cells.iter().filter(|&&c| c > 0).count();
        assert!(covered >= 44, "{tag}: keypoints in {covered}/48 cells");
        // Brute-force matching with a ratio test, checked against the true motion.
        let depth = f0.depth_true.as_ref().unwrap();
        let rel = f1.pose_wc.inverse() * f0.pose_wc;
        let (mut matches, mut correct) = (0, 0);
        for (a, da) in k0.iter().zip(&d0) {
            let (mut best, mut second, mut bi) = (u32::MAX, u32::MAX, 0);
            for (j, db) in d1.iter().enumerate() {
                let h = hamming(da, db);
                if h < best {
                    second = best;
                    best = h;
                    bi = j;
                } else if h < second {
                    second = h;
                }
            }
            if best > 50 || best as f64 > 0.8 * second as f64 {
                continue;
            }
            matches += 1;
            let (u, v) = (a.x.round() as usize, a.y.round() as usize);
            let z = depth.get(u.min(639), v.min(479)).unwrap() as f64;
            let p1 = rel * Point3::from(cam.unproject(a.x as f64, a.y as f64, z));
            let uv = cam.project(&p1.coords);
            let b = &k1[bi];
            if ((uv.x - b.x as f64).powi(2) + (uv.y - b.y as f64).powi(2)).sqrt() < 4.0 {
                correct += 1;
            }
        }
        assert!(matches >= 300, "{tag}: {matches} matches");
        let ratio = correct as f64 / matches as f64;
        assert!(
            ratio > 0.8,
            "{tag}: {correct} of {matches} matches agree with the true motion"
        );
        eprintln!(
            "{tag}: {} keypoints, {covered}/48 cells, {correct}/{matches} correct matches",
            k0.len()
        );
    }
}
