//! CPU seconds per frame of the renderer on a few twins, and a fingerprint of the frames it
//! made, to show that a faster renderer gives the same bytes:
//! `RAYON_NUM_THREADS=1 cargo run --release -p synth --example render_speed -- [FRAMES] [TWINS] [one-ray]`
//! (TWINS: comma-separated preset names; default fr1_desk, fr3_w_rpy, fr2_coke, v101).
//!
//! With `one-ray`, each twin is rendered with one exposure time sample per pixel and no
//! anti-aliasing: one colour ray per pixel (and, as always, one for depth). Those are not the
//! twin's bytes: the figure bounds what any renderer that changes bytes by casting fewer rays
//! could gain while everything else about making a frame stays as it is.
//!
//! Frames 0..FRAMES are generated in order, as `noisefree synth` does (the auto-exposure's
//! metering previews are cached and reused); the CPU time is the process's user + system time
//! (`/proc/self/stat`), so with one rayon thread it is the cost on one core, whatever else
//! the machine runs. The fingerprint is an FNV-1a hash of every frame's images, depths, mask
//! and pose, bit for bit.

use synth::{Generator, Supersampling, SynthConfig};

/// Process user + system CPU time, seconds (Linux).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the command name (which may hold spaces) start after the last ')'.
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the whole line, 12 and 13 after ')'.
    let ticks = |i: usize| f.get(i).and_then(|s| s.parse::<f64>().ok()).unwrap_or(0.0);
    (ticks(11) + ticks(12)) / 100.0
}

/// 64-bit FNV-1a.
fn fnv(mut h: u64, b: &[u8]) -> u64 {
    for &x in b {
        h ^= x as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(6);
    let twins = args
        .get(2)
        .cloned()
        .unwrap_or_else(|| "twin_fr1_desk,twin_fr3_w_rpy,twin_fr2_coke,twin_v101".into());
    let one_ray = match args.get(3).map(String::as_str) {
        None => false,
        Some("one-ray") => true,
        Some(other) => return Err(format!("unknown mode `{other}` (expected `one-ray`)").into()),
    };
    println!(
        "frames 0..{n}{}, one line per twin: setup CPU s, CPU s per frame, FNV-1a of frames",
        if one_ray {
            ", one colour ray per pixel"
        } else {
            ""
        }
    );
    for name in twins.split(',') {
        let c0 = cpu_seconds();
        let mut config = SynthConfig::preset(name)?;
        if one_ray {
            if let Some(e) = config.imaging.exposure.as_mut() {
                e.samples = 1;
            }
            config.image.supersampling = Supersampling::None;
        }
        let gen = Generator::try_new(config, 1)?;
        let c1 = cpu_seconds();
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        for i in 0..n {
            let f = gen.frame(i);
            h = fnv(h, &f.gray.data);
            if let Some(rgb) = &f.rgb {
                h = fnv(h, rgb);
            }
            for d in [&f.depth, &f.depth_true].into_iter().flatten() {
                for x in &d.data {
                    h = fnv(h, &x.to_bits().to_le_bytes());
                }
            }
            if let Some(r) = &f.right {
                h = fnv(h, &r.data);
            }
            if let Some(m) = &f.moving_mask {
                h = fnv(h, &m.iter().map(|&b| b as u8).collect::<Vec<_>>());
            }
            for x in f.pose_wc.to_homogeneous().iter() {
                h = fnv(h, &x.to_bits().to_le_bytes());
            }
        }
        let c2 = cpu_seconds();
        println!(
            "{name:<18} setup {:6.2} s  {:7.3} s/frame  {h:016x}",
            c1 - c0,
            (c2 - c1) / n.max(1) as f64
        );
    }
    Ok(())
}
