//! Fingerprints of what the generator produces, to show that a change of code leaves every
//! byte as it was: run it before and after, and compare the two outputs (they must be equal).
//! `cargo run --release -p synth --example hash_all [SEED]`.
//!
//! Per preset and twin ([`synth::Preset::all`]), and for the `kinect` preset along the other
//! built-in paths and a recorded one: an FNV-1a hash of frames 0, 1, 40 and 125 (grey, colour,
//! measured and true depth, right image, moving-object mask, exact pose and stamps, bit for
//! bit) and of the clocks of frames 0..41 (colour and depth stamps, ground truth as the
//! motion-capture system records it, colour-depth pairs). Then, for one preset of each writer
//! path, an FNV-1a hash of a contact sheet (the folders the generator's frames are written to are
//! hashed by `cargo run --release -p datasets --example hash_written`).

use std::path::Path;

use synth::{Generator, Preset, RecordedPath, SynthConfig, Trajectory};

/// The frames hashed: the first two, a late one (auto-exposure history, lags, people) and one
/// inside the `occluded` preset's occlusion window.
const FRAMES: [usize; 4] = [0, 1, 40, 125];
/// Frames whose clocks are hashed.
const CLOCK_FRAMES: usize = 41;

/// 64-bit FNV-1a.
struct Fnv(u64);

impl Fnv {
    fn new() -> Fnv {
        Fnv(slam_core::hash::FNV1A_OFFSET)
    }
    fn bytes(&mut self, b: &[u8]) {
        self.0 = slam_core::hash::fnv1a_continue(self.0, b);
    }
    fn u64(&mut self, x: u64) {
        self.bytes(&x.to_le_bytes());
    }
    fn f64(&mut self, x: f64) {
        self.u64(x.to_bits());
    }
    fn f32s(&mut self, xs: &[f32]) {
        self.u64(xs.len() as u64);
        for x in xs {
            self.bytes(&x.to_bits().to_le_bytes());
        }
    }
    fn pose(&mut self, p: &nalgebra::Isometry3<f64>) {
        for x in p.translation.vector.iter() {
            self.f64(*x);
        }
        for x in p.rotation.coords.iter() {
            self.f64(*x);
        }
    }
}

/// Hashes of the rendered frames and of the clocks of `gen`.
fn fingerprint(gen: &Generator) -> (u64, u64) {
    let mut h = Fnv::new();
    for i in FRAMES {
        let f = gen.frame(i);
        h.u64(f.index as u64);
        h.f64(f.timestamp);
        h.bytes(&f.gray.data);
        if let Some(rgb) = &f.rgb {
            h.bytes(rgb);
        }
        if let Some(d) = &f.depth {
            h.f32s(&d.data);
        }
        if let Some(d) = &f.depth_true {
            h.f32s(&d.data);
        }
        if let Some(r) = &f.right {
            h.bytes(&r.data);
        }
        if let Some(m) = &f.moving_mask {
            h.bytes(&m.iter().map(|&b| b as u8).collect::<Vec<_>>());
        }
        h.pose(&f.pose_wc);
    }
    let n = CLOCK_FRAMES;
    let mut c = Fnv::new();
    for i in 0..n {
        c.f64(gen.timestamp(i));
        c.f64(gen.depth_timestamp(i));
        c.f64(gen.time(i));
    }
    for (t, pose) in gen.groundtruth(n) {
        c.f64(t);
        c.pose(&pose);
    }
    for (i, j) in gen.stream_pairs(n) {
        c.u64(i as u64);
        c.u64(j as u64);
    }
    (h.0, c.0)
}

/// A recorded hand-held path in TUM's text format: 30 s at 100 Hz of a slow drift with a
/// look-around, as a motion-capture file would give it.
fn recorded_text() -> String {
    let mut s = String::from("# timestamp tx ty tz qx qy qz qw\n");
    for k in 0..3000 {
        let t = k as f64 / 100.0;
        let p =
            nalgebra::Vector3::new(0.6 * (0.2 * t).sin(), 0.4 * (0.13 * t).cos(), 0.1 * t.sin());
        // Camera looking along the world y axis, z forward and y down: a rotation about x by
        // -90 degrees, then a slow yaw and pitch.
        let q = nalgebra::UnitQuaternion::from_euler_angles(-std::f64::consts::FRAC_PI_2, 0.0, 0.0)
            * nalgebra::UnitQuaternion::from_euler_angles(
                0.1 * (0.3 * t).sin(),
                0.4 * (0.1 * t).sin(),
                0.0,
            );
        let q = q.coords;
        s.push_str(&format!(
            "{:.4} {:.6} {:.6} {:.6} {:.7} {:.7} {:.7} {:.7}\n",
            1_305_031_102.0 + t,
            p.x,
            p.y,
            p.z,
            q.x,
            q.y,
            q.z,
            q.w
        ));
    }
    s
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seed: u64 = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(3);
    println!("seed {seed}, frames {FRAMES:?}; FNV-1a of frames | of clocks 0..{CLOCK_FRAMES}");
    let mut cases: Vec<(String, SynthConfig)> = Preset::all()
        .map(|p| (p.name().to_string(), p.config()))
        .collect();
    let recorded = RecordedPath::parse(&recorded_text(), Path::new("recorded.txt"))?;
    for (name, trajectory) in [
        ("rpy", Trajectory::Rpy),
        ("spin", Trajectory::Spin),
        (
            "recorded",
            Trajectory::Recorded(std::sync::Arc::new(recorded)),
        ),
    ] {
        let mut c = Preset::Kinect.config();
        c.trajectory = trajectory;
        cases.push((format!("kinect/{name}"), c));
    }
    for (name, config) in &cases {
        let gen = Generator::try_new(config.clone(), seed)?;
        let (frames, clocks) = fingerprint(&gen);
        println!("{name:<22} {frames:016x} {clocks:016x}");
    }

    let tmp = std::env::temp_dir().join(format!("synth-hash-all-{}", std::process::id()));
    std::fs::create_dir_all(&tmp)?;
    println!("written: FNV-1a of a contact sheet (folders: datasets' hash_written example)");
    for name in [
        "kinect",
        "walking",
        "stereo",
        "twin_fr1_desk",
        "twin_fr2_desk",
        "twin_v101",
    ] {
        let gen = Generator::try_new(SynthConfig::preset(name)?, seed)?;
        let sheet = tmp.join(format!("{name}.png"));
        synth::write_contact_sheet(&gen, 3, 2, &sheet)?;
        let mut h = Fnv::new();
        h.bytes(&std::fs::read(&sheet)?);
        println!("{name:<22} {:016x}", h.0);
    }
    std::fs::remove_dir_all(&tmp)?;
    Ok(())
}
