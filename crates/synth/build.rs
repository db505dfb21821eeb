//! The fingerprint of the code that renders frames: this crate's sources and slam-core's (the
//! camera model), both manifests and the workspace's Cargo.lock (the versions of every
//! dependency). The frame cache (`output::frame_cache`) keys its files by it, so a frame
//! cached by one build of the renderer is never read by another.

use std::path::{Path, PathBuf};

/// FNV-1a over `bytes`, continuing from `h`: `slam_core::hash::fnv1a_continue` written out,
/// since the build script runs before the crates it could take it from are built.
fn fnv1a(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Every file under `path` (or `path` itself), sorted.
fn files(path: &Path, out: &mut Vec<PathBuf>) {
    if path.is_dir() {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(path)
            .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
            .unwrap_or_default();
        entries.sort();
        for e in entries {
            files(&e, out);
        }
    } else if path.is_file() {
        out.push(path.to_path_buf());
    }
}

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let inputs = [
        "src",
        "Cargo.toml",
        "../slam-core/src",
        "../slam-core/Cargo.toml",
        "../../Cargo.lock",
    ];
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for rel in inputs {
        let path = manifest.join(rel);
        if !path.exists() {
            continue;
        }
        println!("cargo:rerun-if-changed={}", path.display());
        let mut list = Vec::new();
        files(&path, &mut list);
        for f in list {
            let name = f.strip_prefix(&manifest).unwrap_or(&f).to_string_lossy();
            h = fnv1a(h, name.as_bytes());
            h = fnv1a(h, &std::fs::read(&f).unwrap_or_default());
        }
    }
    println!("cargo:rustc-env=SYNTH_CODE_FINGERPRINT={h:016x}");
}
