//! Writes a generated RGB-D sequence in exactly the TUM RGB-D layout: `rgb/<stamp>.png`
//! (8-bit RGB), `depth/<stamp>.png` (16-bit, the configuration's units per metre, 5000 but for
//! the fr2 twins' 5208, 0 = no depth), each image
//! named by its own stream's stamp, `rgb.txt`, `depth.txt`, `groundtruth.txt` (`timestamp tx
//! ty tz qx qy qz qw`, [`Generator::groundtruth`]: with the motion-capture noise and clock the
//! configuration has) and `associations.txt` (`t_rgb rgb/x.png t_depth depth/y.png`, the pairs
//! TUM's associate.py finds in the two lists: [`Generator::stream_pairs`]).

use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use image::ExtendedColorType;
use nalgebra::Isometry3;
use rayon::prelude::*;

use crate::error::SynthError;
use crate::generator::Generator;
use crate::motion::clock::stamp_name;
use crate::output::write::{mkdir, png, text, Staging};

/// One TUM trajectory line `timestamp tx ty tz qx qy qz qw` (qw >= 0).
pub fn pose_line(timestamp: f64, pose: &Isometry3<f64>) -> String {
    let t = pose.translation.vector;
    let mut q = *pose.rotation.quaternion();
    if q.w < 0.0 {
        q = -q;
    }
    format!(
        "{timestamp:.6} {:.9} {:.9} {:.9} {:.9} {:.9} {:.9} {:.9}",
        t.x, t.y, t.z, q.i, q.j, q.k, q.w
    )
}

/// Writes frames 0..n of `gen` (an RGB-D generator) into `dir` in the TUM RGB-D layout.
/// Frames are generated and encoded in parallel; `progress(k)` is called with the number of
/// frames written so far. Everything goes to a staging folder renamed to `dir` at the end;
/// `dir` must not exist or be empty; frames beyond a recorded trajectory are refused first
/// ([`Generator::check_frames`]).
pub fn write_tum(
    gen: &Generator,
    n: usize,
    dir: &Path,
    progress: impl Fn(usize) + Sync,
) -> Result<(), SynthError> {
    if !gen.config().is_rgbd() {
        return Err(SynthError::InvalidConfig(
            "the TUM layout needs an RGB-D configuration (use write_euroc for stereo)".into(),
        ));
    }
    gen.check_frames(n)?;
    Staging::write_atomically(dir, |tmp| write_into(gen, n, tmp, &progress))
}

fn write_into(
    gen: &Generator,
    n: usize,
    root: &Path,
    progress: &(impl Fn(usize) + Sync),
) -> Result<(), SynthError> {
    let (rgb_dir, depth_dir) = (root.join("rgb"), root.join("depth"));
    mkdir(&rgb_dir)?;
    mkdir(&depth_dir)?;
    let done = AtomicUsize::new(0);
    let units = gen.config().depth_units_per_metre;
    (0..n)
        .into_par_iter()
        .try_for_each(|i| -> Result<(), SynthError> {
            let f = gen.frame(i);
            let name = format!("{}.png", stamp_name(f.timestamp));
            let depth_name = format!("{}.png", stamp_name(gen.depth_timestamp(i)));
            let (w, h) = (f.gray.width, f.gray.height);
            if let Some(rgb) = &f.rgb {
                png(&rgb_dir.join(&name), rgb, w, h, ExtendedColorType::Rgb8)?;
            }
            if let Some(d) = &f.depth {
                let bytes: Vec<u8> = d
                    .data
                    .iter()
                    .flat_map(|&z| {
                        ((z as f64 * units).round().clamp(0.0, 65535.0) as u16).to_ne_bytes()
                    })
                    .collect();
                png(
                    &depth_dir.join(&depth_name),
                    &bytes,
                    w,
                    h,
                    ExtendedColorType::L16,
                )?;
            }
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            Ok(())
        })?;
    let what = format!(
        "synthetic noisefree sequence, seed {}, trajectory {}",
        gen.seed(),
        gen.config().trajectory.name()
    );
    let mut rgb_txt = format!("# color images\n# file: '{what}'\n# timestamp filename\n");
    let mut depth_txt = format!("# depth maps\n# file: '{what}'\n# timestamp filename\n");
    let mut gt =
        format!("# ground truth trajectory\n# file: '{what}'\n# timestamp tx ty tz qx qy qz qw\n");
    let mut assoc = String::new();
    // Infallible: writing into a String.
    for i in 0..n {
        let s = stamp_name(gen.timestamp(i));
        let d = stamp_name(gen.depth_timestamp(i));
        let _ = writeln!(rgb_txt, "{s} rgb/{s}.png");
        let _ = writeln!(depth_txt, "{d} depth/{d}.png");
    }
    for (i, j) in gen.stream_pairs(n) {
        let s = stamp_name(gen.timestamp(i));
        let d = stamp_name(gen.depth_timestamp(j));
        let _ = writeln!(assoc, "{s} rgb/{s}.png {d} depth/{d}.png");
    }
    for (t, pose) in gen.groundtruth(n) {
        let _ = writeln!(gt, "{}", pose_line(t, &pose));
    }
    text(&root.join("rgb.txt"), &rgb_txt)?;
    text(&root.join("depth.txt"), &depth_txt)?;
    text(&root.join("groundtruth.txt"), &gt)?;
    text(&root.join("associations.txt"), &assoc)
}
