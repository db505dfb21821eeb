//! Fingerprints of the folders the writer makes from generated frames, to show that a change of
//! code leaves every byte of them as it was: run it before and after and compare the outputs.
//! `cargo run --release -p datasets --example hash_written [SEED]` (default seed 3, as synth's
//! `hash_all`, whose frame hashes cover what is rendered).
//!
//! For one preset of each writer path (TUM at 5000 and 5208 units per metre, a rectified
//! EuRoC pair, a calibrated EuRoC rig): an FNV-1a hash of every file of a 3-frame folder, names
//! and bytes, in path order.

use std::path::{Path, PathBuf};

use synth::{Generator, SynthConfig};

/// 64-bit FNV-1a of every file under `dir`: its path relative to `dir`, then its bytes.
fn hash_folder(dir: &Path) -> Result<u64, std::io::Error> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) -> Result<(), std::io::Error> {
        let mut entries = std::fs::read_dir(dir)?
            .map(|e| e.map(|e| e.path()))
            .collect::<Result<Vec<_>, _>>()?;
        entries.sort();
        for p in entries {
            if p.is_dir() {
                walk(&p, out)?;
            } else {
                out.push(p);
            }
        }
        Ok(())
    }
    let mut files = Vec::new();
    walk(dir, &mut files)?;
    let mut h = slam_core::hash::FNV1A_OFFSET;
    for f in files {
        let rel = f
            .strip_prefix(dir)
            .unwrap_or(&f)
            .to_string_lossy()
            .into_owned();
        h = slam_core::hash::fnv1a_continue(h, rel.as_bytes());
        h = slam_core::hash::fnv1a_continue(h, &std::fs::read(&f)?);
    }
    Ok(h)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seed: u64 = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(3);
    let tmp = std::env::temp_dir().join(format!("datasets-hash-written-{}", std::process::id()));
    std::fs::create_dir_all(&tmp)?;
    for name in [
        "kinect",
        "walking",
        "stereo",
        "twin_fr1_desk",
        "twin_fr2_desk",
        "twin_v101",
    ] {
        let gen = Generator::try_new(SynthConfig::preset(name)?, seed)?;
        let dir = tmp.join(name);
        datasets::write::write_synthetic(&gen, 3, &dir, |_| {})?;
        println!("{name:<22} {:016x}", hash_folder(&dir)?);
    }
    std::fs::remove_dir_all(&tmp)?;
    Ok(())
}
