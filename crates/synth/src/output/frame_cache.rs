//! A folder of rendered frames that processes share: a frame is a pure function of the
//! renderer's code, the configuration, the seed and the frame index, so a process that needs a
//! frame another process (or an earlier run) rendered can read it instead of rendering it
//! again. What is kept is what a SLAM system is given of the frame (grey image, measured depth,
//! right image, the colour image of an RGB-D frame, stamp) and its exact pose, bit for bit.
//!
//! Files live in a subfolder named by the code ([`CODE_FINGERPRINT`]: the sources of this crate
//! and slam-core, the manifests and Cargo.lock, fixed at build time), about 1.8 MB a 640 x 480
//! RGB-D frame with its colour. Every process that uses a build's subfolder marks it used; a
//! process removes the subfolders of other builds unused for [`STALE_AFTER`], and of the others
//! the least recently used first while the folder is over its cap. So two builds can share a
//! folder (a long sweep of an installed binary beside the build being worked on) without each
//! deleting the other's frames, while the frames of builds nobody runs any more do not pile
//! up. Each file is named by a key of the code, the machine's
//! architecture, the seed and the whole configuration, and by the frame index; it carries the
//! key again and a checksum. A file that is missing, truncated, corrupt or of another key is
//! ignored: the frame is rendered and the file written anew (to a temporary name, then renamed,
//! so no reader ever sees half a file). Nothing here is required: without a folder every frame
//! is rendered, and a folder that cannot be written only costs the renders.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use crate::hash::mix64;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use slam_core::hash::{fnv1a, fnv1a_continue};
use slam_core::{ColourImage, DepthImage, FrameInput, GrayImage};

use crate::generator::Generator;

/// The fingerprint of the rendering code this build was compiled from (see the module doc).
pub const CODE_FINGERPRINT: &str = env!("SYNTH_CODE_FINGERPRINT");

/// The environment variable naming a frame-cache folder for the command-line tool (unset: no
/// cache). The test suites set it so that their processes share renders.
pub const CACHE_ENV: &str = "NOISEFREE_SYNTH_CACHE";

/// The environment variable capping what processes add to a frame cache, in gigabytes
/// (default [`DEFAULT_LIMIT_GB`]).
pub const CACHE_LIMIT_ENV: &str = "NOISEFREE_SYNTH_CACHE_GB";

/// The default cap on a frame cache's size, gigabytes: a twin of a whole sequence is 1-7 GB
/// of frames, every twin of Table III about 100 GB, more than many disks have free.
pub const DEFAULT_LIMIT_GB: f64 = 20.0;

/// [`DEFAULT_LIMIT_GB`] in bytes.
const DEFAULT_LIMIT: u64 = (DEFAULT_LIMIT_GB * 1e9) as u64;

/// The cap [`CACHE_LIMIT_ENV`] sets, bytes (the default when it is unset or empty); an error
/// naming the variable when it is not a number of gigabytes at least 0.
pub fn cache_limit_from_env() -> Result<u64, String> {
    let Some(v) = std::env::var_os(CACHE_LIMIT_ENV).filter(|v| !v.is_empty()) else {
        return Ok(DEFAULT_LIMIT);
    };
    let text = v.to_string_lossy();
    match text.trim().parse::<f64>() {
        Ok(gb) if gb.is_finite() && gb >= 0.0 => Ok((gb * 1e9) as u64),
        _ => Err(format!(
            "{CACHE_LIMIT_ENV}={text}: expected the frame cache's cap in gigabytes (a number >= 0)"
        )),
    }
}

/// The folder named by [`CACHE_ENV`], when it is set and not empty; an error when
/// [`CACHE_LIMIT_ENV`] is set to something that is not a cap (see [`cache_limit_from_env`]),
/// so a tool refuses it before anything runs rather than storing under the default.
pub fn cache_dir_from_env() -> Result<Option<PathBuf>, String> {
    cache_limit_from_env()?;
    Ok(std::env::var_os(CACHE_ENV)
        .filter(|v| !v.is_empty())
        .map(PathBuf::from))
}

/// How long a build's subfolder stays after its last use: another build's process removes
/// it after that. A process marks its folder while it reads or stores frames; one that works
/// longer than this on frames it holds (a sweep's runs) may find them removed when it comes
/// back, and then renders them again, the same bytes.
pub const STALE_AFTER: std::time::Duration = std::time::Duration::from_secs(600);

/// Reads between two marks of use on a build's subfolder by a process that only reads.
const MARK_EVERY: usize = 64;

/// First bytes of a cached frame file.
const MAGIC: &[u8; 8] = b"NFSYNTH3";

/// A generator's frames as a SLAM system gets them, read from a cache folder when they are
/// there and rendered (and stored there) when not.
#[derive(Clone, Debug)]
pub struct CachedFrames {
    gen: Generator,
    dir: Option<Arc<PathBuf>>,
    key: u64,
    /// Bytes this value (and its clones) may still add to the folder.
    budget: Arc<AtomicU64>,
}

impl CachedFrames {
    /// The frames of `gen`, cached in `dir` (`None`: always rendered), the folder kept under
    /// the cap of [`CACHE_LIMIT_ENV`] (an unreadable value counts as the default;
    /// [`cache_dir_from_env`] refuses it first). The frames of other builds of the renderer
    /// unused for [`STALE_AFTER`] are removed from `dir`.
    pub fn new(gen: Generator, dir: Option<&Path>) -> Self {
        let limit = cache_limit_from_env().unwrap_or(DEFAULT_LIMIT);
        Self::with_limit(gen, dir, limit)
    }

    /// [`CachedFrames::new`] with a cap of `limit` bytes: other builds' frames are removed,
    /// least recently used first, while the folder is over it; frames are stored only while
    /// the folder (every build's frames in it, as measured here, plus what this value stored
    /// since) stays under it; past it, frames are rendered and not stored. Processes writing
    /// the same folder at once each count from what they found, so together they may pass the
    /// cap by what each adds.
    pub fn with_limit(gen: Generator, dir: Option<&Path>, limit: u64) -> Self {
        let key = dir.map_or(0, |_| generator_key(&gen));
        let (dir, used) = dir.map(|d| settle_folder(d, limit)).unzip();
        let (dir, used) = (dir.map(Arc::new), used.unwrap_or(0));
        CachedFrames {
            gen,
            dir,
            key,
            budget: Arc::new(AtomicU64::new(limit.saturating_sub(used))),
        }
    }

    /// Frame `index` as a SLAM system is given it (what [`crate::SynthFrame::into_input`]
    /// keeps) and its exact camera-to-world pose: the same bits whether read or rendered.
    pub fn input(&self, index: usize) -> (FrameInput, Isometry3<f64>) {
        let Some(dir) = &self.dir else {
            return rendered(&self.gen, index);
        };
        let path = dir.join(format!("{:016x}-{index}.frame", self.key));
        if let Some(frame) = std::fs::read(&path)
            .ok()
            .and_then(|b| decode(&b, self.key, index))
        {
            if index.is_multiple_of(MARK_EVERY) {
                mark_used(dir);
            }
            return frame;
        }
        let (input, pose) = rendered(&self.gen, index);
        let units = self.gen.config().depth_units_per_metre;
        let bytes = encode(self.key, index, &input, &pose, units);
        let size = bytes.len() as u64;
        let afforded = self
            .budget
            .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |b| {
                b.checked_sub(size)
            })
            .is_ok();
        // Best effort: a folder that is full or cannot be written costs renders, not results.
        if afforded {
            let _ = atomic_file::write(&path, &bytes);
        }
        (input, pose)
    }
}

/// The bytes of the files directly in `dir` (0 when it cannot be read).
fn folder_bytes(dir: &Path) -> u64 {
    std::fs::read_dir(dir).map_or(0, |entries| {
        entries
            .flatten()
            .filter_map(|e| e.metadata().ok())
            .filter(|m| m.is_file())
            .map(|m| m.len())
            .sum()
    })
}

/// This build's subfolder of the cache folder `dir` (made when it is not there yet, and marked
/// used) and the bytes of every build's frames in `dir` once other builds' subfolders are
/// removed: those unused for [`STALE_AFTER`], then the least recently used first while the
/// folder is over `limit` (best effort: what cannot be removed or dated stays, and counts).
fn settle_folder(dir: &Path, limit: u64) -> (PathBuf, u64) {
    let own = dir.join(CODE_FINGERPRINT);
    let _ = std::fs::create_dir_all(&own);
    mark_used(&own);
    let now = std::time::SystemTime::now();
    let mut used = 0;
    let mut others = Vec::new();
    for (path, last_use) in builds(dir) {
        let stale = last_use
            .and_then(|t| now.duration_since(t).ok())
            .is_some_and(|age| age > STALE_AFTER);
        if path != own && stale && std::fs::remove_dir_all(&path).is_ok() {
            continue;
        }
        let bytes = folder_bytes(&path);
        used += bytes;
        if path != own {
            others.push((last_use, path, bytes));
        }
    }
    others.sort_by_key(|o| o.0);
    for (_, path, bytes) in others {
        if used <= limit {
            break;
        }
        if std::fs::remove_dir_all(&path).is_ok() {
            used -= bytes;
        }
    }
    (own, used)
}

/// The builds' subfolders of `dir` (16 hexadecimal digits) with their last use.
fn builds(dir: &Path) -> Vec<(PathBuf, Option<std::time::SystemTime>)> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter(|e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            name.len() == 16 && name.bytes().all(|b| b.is_ascii_hexdigit())
        })
        .filter(|e| e.path().is_dir())
        .map(|e| (e.path(), e.metadata().and_then(|m| m.modified()).ok()))
        .collect()
}

/// Marks a build's subfolder used now (its modification time; best effort).
fn mark_used(own: &Path) {
    if let Ok(f) = std::fs::File::open(own) {
        let _ = f.set_modified(std::time::SystemTime::now());
    }
}

/// The frame rendered.
fn rendered(gen: &Generator, index: usize) -> (FrameInput, Isometry3<f64>) {
    let frame = gen.frame(index);
    let pose = frame.pose_wc;
    (frame.into_input(), pose)
}

/// The key of `gen`'s frames: code, architecture, seed and configuration (its `Debug` form
/// prints every field, floats in their shortest round-trip form).
fn generator_key(gen: &Generator) -> u64 {
    let mut h = fnv1a(CODE_FINGERPRINT.as_bytes());
    h = fnv1a_continue(h, std::env::consts::ARCH.as_bytes());
    h = fnv1a_continue(h, &gen.seed().to_le_bytes());
    fnv1a_continue(h, format!("{:?}", gen.config()).as_bytes())
}

/// How a depth image is stored: as the 16-bit units the generator quantised it to when every
/// pixel comes back bit for bit from them, else as its f32 values.
const DEPTH_NONE: u8 = 0;
const DEPTH_UNITS: u8 = 1;
const DEPTH_F32: u8 = 2;

/// Depth `d` as the unit count `k` that `(k / units) as f32` gives back exactly (0: a hole).
fn depth_units(d: f32, units: f64) -> Option<u16> {
    if d.to_bits() == 0 {
        return Some(0);
    }
    let k = (f64::from(d) * units).round();
    if !(1.0..=65535.0).contains(&k) {
        return None;
    }
    ((k / units) as f32)
        .to_bits()
        .eq(&d.to_bits())
        .then_some(k as u16)
}

/// The file of one frame.
fn encode(
    key: u64,
    index: usize,
    input: &FrameInput,
    pose: &Isometry3<f64>,
    units: f64,
) -> Vec<u8> {
    let mut b = Vec::with_capacity(input.image.data.len() * 4 + 256);
    b.extend_from_slice(MAGIC);
    b.extend_from_slice(&key.to_le_bytes());
    b.extend_from_slice(&(index as u64).to_le_bytes());
    b.extend_from_slice(&input.timestamp.to_le_bytes());
    let t = pose.translation.vector;
    let q = pose.rotation.coords;
    for x in [t.x, t.y, t.z, q[0], q[1], q[2], q[3]] {
        b.extend_from_slice(&x.to_le_bytes());
    }
    let gray = |b: &mut Vec<u8>, g: &GrayImage| {
        b.extend_from_slice(&(g.width as u32).to_le_bytes());
        b.extend_from_slice(&(g.height as u32).to_le_bytes());
        b.extend_from_slice(&g.data);
    };
    gray(&mut b, &input.image);
    match &input.depth {
        None => b.push(DEPTH_NONE),
        Some(d) => {
            let as_units: Option<Vec<u16>> =
                d.data.iter().map(|&z| depth_units(z, units)).collect();
            b.push(if as_units.is_some() {
                DEPTH_UNITS
            } else {
                DEPTH_F32
            });
            b.extend_from_slice(&(d.width as u32).to_le_bytes());
            b.extend_from_slice(&(d.height as u32).to_le_bytes());
            match as_units {
                Some(k) => {
                    b.extend_from_slice(&units.to_le_bytes());
                    k.iter().for_each(|k| b.extend_from_slice(&k.to_le_bytes()));
                }
                None => d
                    .data
                    .iter()
                    .for_each(|z| b.extend_from_slice(&z.to_le_bytes())),
            }
        }
    }
    match &input.right {
        None => b.push(0),
        Some(r) => {
            b.push(1);
            gray(&mut b, r);
        }
    }
    match &input.colour {
        None => b.push(0),
        Some(c) => {
            b.push(1);
            b.extend_from_slice(&(c.width as u32).to_le_bytes());
            b.extend_from_slice(&(c.height as u32).to_le_bytes());
            b.extend_from_slice(&c.data);
        }
    }
    let sum = checksum(&b);
    b.extend_from_slice(&sum.to_le_bytes());
    b
}

/// The checksum a cached file ends with: four lanes of multiply-xor over 8-byte words, mixed
/// together with the length. It only has to notice a damaged file (any changed word changes its
/// lane, each step being a bijection of the lane); FNV-1a's one byte at a time cost 1.5-2 ms of
/// the 1.8 MB a frame holds, every time a frame was read.
fn checksum(bytes: &[u8]) -> u64 {
    const K: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut lanes = [K, K.rotate_left(16), K.rotate_left(32), K.rotate_left(48)];
    let mut blocks = bytes.chunks_exact(32);
    for block in &mut blocks {
        for (lane, word) in lanes.iter_mut().zip(block.chunks_exact(8)) {
            let w = u64::from_le_bytes(word.try_into().expect("8 bytes"));
            *lane = (*lane ^ w)
                .wrapping_mul(0x0000_0100_0000_01b3)
                .rotate_left(27);
        }
    }
    let tail = fnv1a(blocks.remainder());
    let mut h = mix64(bytes.len() as u64 ^ tail);
    for lane in lanes {
        h = mix64(h ^ lane);
    }
    h
}

/// Reads the file of frame `index` of key `key`; `None` unless it is whole and that frame's.
fn decode(bytes: &[u8], key: u64, index: usize) -> Option<(FrameInput, Isometry3<f64>)> {
    let (body, sum) = bytes.split_at_checked(bytes.len().checked_sub(8)?)?;
    if checksum(body) != u64::from_le_bytes(sum.try_into().ok()?) {
        return None;
    }
    let mut r = Reader(body);
    if r.take(8)? != MAGIC || r.u64()? != key || r.u64()? != index as u64 {
        return None;
    }
    let timestamp = r.f64()?;
    let mut p = [0.0; 7];
    for x in &mut p {
        *x = r.f64()?;
    }
    let pose = Isometry3::from_parts(
        Translation3::new(p[0], p[1], p[2]),
        UnitQuaternion::new_unchecked(Quaternion::new(p[6], p[3], p[4], p[5])),
    );
    let image = r.gray()?;
    let depth = match r.take(1)?[0] {
        DEPTH_NONE => None,
        tag @ (DEPTH_UNITS | DEPTH_F32) => {
            let (width, height) = r.size()?;
            let data = if tag == DEPTH_UNITS {
                let units = r.f64()?;
                r.take(width * height * 2)?
                    .chunks_exact(2)
                    .map(|k| (f64::from(u16::from_le_bytes([k[0], k[1]])) / units) as f32)
                    .collect()
            } else {
                r.take(width * height * 4)?
                    .chunks_exact(4)
                    .map(|z| f32::from_le_bytes([z[0], z[1], z[2], z[3]]))
                    .collect()
            };
            Some(Arc::new(DepthImage {
                width,
                height,
                data,
            }))
        }
        _ => return None,
    };
    let right = match r.take(1)?[0] {
        0 => None,
        1 => Some(Arc::new(r.gray()?)),
        _ => return None,
    };
    let colour = match r.take(1)?[0] {
        0 => None,
        1 => {
            let (width, height) = r.size()?;
            let data = r.take(width.checked_mul(height)?.checked_mul(3)?)?.to_vec();
            Some(Arc::new(ColourImage {
                width,
                height,
                data,
            }))
        }
        _ => return None,
    };
    if !r.0.is_empty() {
        return None;
    }
    let input = FrameInput {
        timestamp,
        image: Arc::new(image),
        depth,
        right,
        colour,
    };
    Some((input, pose))
}

/// A cursor over a file's bytes.
struct Reader<'a>(&'a [u8]);

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let (head, rest) = self.0.split_at_checked(n)?;
        self.0 = rest;
        Some(head)
    }

    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }

    fn f64(&mut self) -> Option<f64> {
        Some(f64::from_bits(self.u64()?))
    }

    fn size(&mut self) -> Option<(usize, usize)> {
        let w = u32::from_le_bytes(self.take(4)?.try_into().ok()?) as usize;
        let h = u32::from_le_bytes(self.take(4)?.try_into().ok()?) as usize;
        Some((w, h))
    }

    fn gray(&mut self) -> Option<GrayImage> {
        let (width, height) = self.size()?;
        let data = self.take(width.checked_mul(height)?)?.to_vec();
        Some(GrayImage {
            width,
            height,
            data,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SynthConfig;

    fn same(a: &(FrameInput, Isometry3<f64>), b: &(FrameInput, Isometry3<f64>)) {
        assert_eq!(a.0.timestamp.to_bits(), b.0.timestamp.to_bits());
        assert_eq!(a.0.image.data, b.0.image.data);
        assert_eq!(
            (a.0.image.width, a.0.image.height),
            (b.0.image.width, b.0.image.height)
        );
        let bits = |d: &Option<Arc<DepthImage>>| {
            d.as_ref().map(|d| {
                (
                    d.width,
                    d.height,
                    d.data.iter().map(|z| z.to_bits()).collect::<Vec<_>>(),
                )
            })
        };
        assert_eq!(bits(&a.0.depth), bits(&b.0.depth));
        assert_eq!(
            a.0.right.as_ref().map(|r| r.data.clone()),
            b.0.right.as_ref().map(|r| r.data.clone())
        );
        let pose = |p: &Isometry3<f64>| {
            let t = p.translation.vector;
            let q = p.rotation.coords;
            [t.x, t.y, t.z, q[0], q[1], q[2], q[3]].map(f64::to_bits)
        };
        assert_eq!(pose(&a.1), pose(&b.1));
    }

    /// Small frames of a preset, so that the test renders in milliseconds.
    fn small(preset: &str) -> Generator {
        let mut cfg = SynthConfig::preset(preset).unwrap();
        let c = &mut cfg.camera;
        (c.width, c.height) = (c.width / 8, c.height / 8);
        for x in [&mut c.fx, &mut c.fy, &mut c.cx, &mut c.cy, &mut c.bf] {
            *x /= 8.0;
        }
        Generator::new(cfg, 3)
    }

    #[test]
    fn a_cached_frame_is_the_rendered_frame_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        // Depth (quantised to the PNG's units as every preset does: stored as units) and a
        // stereo pair.
        for preset in ["kinect", "clean", "stereo"] {
            let gen = small(preset);
            let plain = CachedFrames::new(gen.clone(), None);
            let cached = CachedFrames::new(gen.clone(), Some(dir.path()));
            for i in [0, 7] {
                let fresh = plain.input(i);
                let first = cached.input(i); // rendered, then written
                let again = cached.input(i); // read
                same(&fresh, &first);
                same(&fresh, &again);
                let path = cached
                    .dir
                    .as_ref()
                    .unwrap()
                    .join(format!("{:016x}-{i}.frame", cached.key));
                let bytes = std::fs::read(&path).unwrap();
                // The depth tag follows the header (88 bytes) and the grey image (8 + w h).
                let img = &fresh.0.image;
                let tag = bytes[88 + 8 + img.width * img.height];
                let expected = match preset {
                    "stereo" => DEPTH_NONE,
                    _ => DEPTH_UNITS,
                };
                assert_eq!(tag, expected, "{preset}: depth stored as {tag}");
            }
        }
    }

    #[test]
    fn depth_off_the_units_is_kept_as_it_is() {
        let image = Arc::new(GrayImage {
            width: 3,
            height: 2,
            data: vec![1, 2, 3, 4, 5, 6],
        });
        let pose = Isometry3::translation(0.1, -0.2, 0.3);
        // Quantised depth with one value between units, a negative zero and a NaN.
        let depth = DepthImage {
            width: 3,
            height: 2,
            data: vec![
                1.0,
                0.0,
                (1234.0f64 / 5000.0) as f32,
                0.2469,
                -0.0,
                f32::NAN,
            ],
        };
        let input = FrameInput {
            timestamp: 12.5,
            image,
            depth: Some(Arc::new(depth)),
            right: None,
            colour: None,
        };
        let bytes = encode(7, 1, &input, &pose, 5000.0);
        assert_eq!(bytes[88 + 8 + 6], DEPTH_F32);
        same(&decode(&bytes, 7, 1).unwrap(), &(input.clone(), pose));
        // On the units but for the last three: stored as units.
        let mut on_units = input.clone();
        on_units.depth = Some(Arc::new(DepthImage {
            width: 3,
            height: 1,
            data: vec![1.0, 0.0, (1234.0f64 / 5000.0) as f32],
        }));
        let bytes = encode(7, 1, &on_units, &pose, 5000.0);
        assert_eq!(bytes[88 + 8 + 6], DEPTH_UNITS);
        same(&decode(&bytes, 7, 1).unwrap(), &(on_units, pose));
    }

    #[test]
    fn a_damaged_or_foreign_file_is_rendered_again() {
        let dir = tempfile::tempdir().unwrap();
        let gen = small("kinect");
        let cached = CachedFrames::new(gen.clone(), Some(dir.path()));
        let fresh = CachedFrames::new(gen.clone(), None).input(2);
        let path = cached
            .dir
            .as_ref()
            .unwrap()
            .join(format!("{:016x}-2.frame", cached.key));
        cached.input(2);
        let whole = std::fs::read(&path).unwrap();
        assert!(decode(&whole, cached.key, 2).is_some());
        // Truncated, a flipped byte, another frame's file, another key: not read.
        assert!(decode(&whole[..whole.len() - 9], cached.key, 2).is_none());
        let mut flipped = whole.clone();
        flipped[200] ^= 1;
        assert!(decode(&flipped, cached.key, 2).is_none());
        assert!(decode(&whole, cached.key, 3).is_none());
        assert!(decode(&whole, cached.key ^ 1, 2).is_none());
        // A damaged file on disk is replaced by the frame rendered again.
        std::fs::write(&path, &flipped).unwrap();
        same(&cached.input(2), &fresh);
        assert_eq!(std::fs::read(&path).unwrap(), whole);
    }

    #[test]
    fn the_checksum_notices_any_changed_byte() {
        let body: Vec<u8> = (0..1000u32).map(|i| (i * 37 % 251) as u8).collect();
        let sum = checksum(&body);
        // Every byte (words of each lane, the tail past the last 32-byte block), any bit.
        for i in 0..body.len() {
            for bit in [0, 3, 7] {
                let mut b = body.clone();
                b[i] ^= 1 << bit;
                assert_ne!(checksum(&b), sum, "byte {i} bit {bit}");
            }
        }
        // Cut short, or a zero byte added: the length counts.
        assert_ne!(checksum(&body[..999]), sum);
        let mut longer = body.clone();
        longer.push(0);
        assert_ne!(checksum(&longer), sum);
        // Two words swapped between lanes.
        let mut swapped = body.clone();
        swapped.copy_within(0..8, 992);
        swapped[..8].copy_from_slice(&body[992..1000]);
        assert_ne!(checksum(&swapped), sum);
    }

    /// Another build's subfolder of `dir`, one frame file of `bytes` bytes, last used `age_s`
    /// seconds ago.
    fn other_build(dir: &Path, name: &str, age_s: u64, bytes: usize) -> PathBuf {
        let d = dir.join(name);
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(d.join("0000000000000000-0.frame"), vec![0u8; bytes]).unwrap();
        let t = std::time::SystemTime::now() - std::time::Duration::from_secs(age_s);
        std::fs::File::open(&d).unwrap().set_modified(t).unwrap();
        d
    }

    #[test]
    fn other_builds_frames_stay_while_used_and_go_once_stale() {
        let dir = tempfile::tempdir().unwrap();
        let (d, stale_s) = (dir.path(), STALE_AFTER.as_secs());
        let stale = other_build(d, "0123456789abcdef", stale_s + 60, 5);
        let recent = other_build(d, "fedcba9876543210", stale_s - 60, 5);
        let not_ours = dir.path().join("notes");
        std::fs::create_dir_all(&not_ours).unwrap();
        let cached = CachedFrames::new(small("kinect"), Some(dir.path()));
        assert!(
            !stale.exists(),
            "a build unused for longer than STALE_AFTER removed"
        );
        assert!(recent.is_dir(), "a build used within STALE_AFTER kept");
        assert!(not_ours.is_dir(), "what is not a build's folder stays");
        let own = dir.path().join(CODE_FINGERPRINT);
        assert_eq!(cached.dir.as_deref(), Some(&own));
        cached.input(0);
        // This build's frames stay for its next processes, and its folder is marked used.
        let again = CachedFrames::new(small("kinect"), Some(dir.path()));
        assert_eq!(
            std::fs::read_dir(again.dir.as_deref().unwrap())
                .unwrap()
                .count(),
            1
        );
        let age = std::fs::metadata(&own)
            .unwrap()
            .modified()
            .unwrap()
            .elapsed();
        assert!(matches!(age, Ok(a) if a < STALE_AFTER / 2), "{age:?}");
        // The cap counts every build's frames in the folder: with room for this build's
        // frames and one more, less the other build's 5 bytes, nothing more is stored.
        let gen = small("kinect");
        let (input, pose) = CachedFrames::new(gen.clone(), None).input(1);
        let units = gen.config().depth_units_per_metre;
        let one = encode(generator_key(&gen), 1, &input, &pose, units).len() as u64;
        let limit = folder_bytes(&own) + one + 2;
        let full = CachedFrames::with_limit(gen.clone(), Some(dir.path()), limit);
        let before = std::fs::read_dir(&own).unwrap().count();
        full.input(1);
        assert_eq!(std::fs::read_dir(&own).unwrap().count(), before);
    }

    #[test]
    fn over_the_cap_the_least_recently_used_other_build_goes_first() {
        let dir = tempfile::tempdir().unwrap();
        let own = dir.path().join(CODE_FINGERPRINT);
        std::fs::create_dir_all(&own).unwrap();
        std::fs::write(own.join("0000000000000000-0.frame"), [0u8; 100]).unwrap();
        let older = other_build(dir.path(), "0123456789abcdef", 120, 10);
        let newer = other_build(dir.path(), "fedcba9876543210", 60, 10);
        // 120 bytes in all; a cap of 115 needs one of the others gone, the older one.
        let cached = CachedFrames::with_limit(small("kinect"), Some(dir.path()), 115);
        assert!(!older.exists(), "the least recently used build removed");
        assert!(newer.is_dir(), "the cap is met without removing the other");
        assert!(
            own.join("0000000000000000-0.frame").is_file(),
            "this build's frames stay"
        );
        assert_eq!(cached.budget.load(Ordering::Relaxed), 5);
        // Under the cap nothing goes.
        CachedFrames::with_limit(small("kinect"), Some(dir.path()), 1000);
        assert!(newer.is_dir());
    }

    #[test]
    fn a_full_cache_renders_and_stores_nothing_more() {
        let dir = tempfile::tempdir().unwrap();
        let gen = small("kinect");
        let count = |c: &CachedFrames| {
            std::fs::read_dir(c.dir.as_deref().unwrap())
                .unwrap()
                .count()
        };
        // Room for two frames: the third is rendered, the same bits, and not stored.
        let (input, pose) = CachedFrames::new(gen.clone(), None).input(0);
        let units = gen.config().depth_units_per_metre;
        let one = encode(generator_key(&gen), 0, &input, &pose, units).len() as u64;
        let cached = CachedFrames::with_limit(gen.clone(), Some(dir.path()), 2 * one + one / 2);
        for i in 0..3 {
            same(
                &cached.input(i),
                &CachedFrames::new(gen.clone(), None).input(i),
            );
        }
        assert_eq!(count(&cached), 2);
        // A later process finds the folder at its cap and adds nothing; it still reads.
        let later = CachedFrames::with_limit(gen.clone(), Some(dir.path()), 2 * one + one / 2);
        later.input(3);
        assert_eq!(count(&later), 2);
        same(
            &later.input(1),
            &CachedFrames::new(gen.clone(), None).input(1),
        );
        // A higher cap lets it store again.
        let roomier = CachedFrames::with_limit(gen.clone(), Some(dir.path()), 4 * one);
        roomier.input(3);
        assert_eq!(count(&roomier), 3);
    }

    #[test]
    fn the_cache_cap_is_read_in_gigabytes_and_refused_when_not_a_number() {
        // The only test that sets the variable; a test reading it meanwhile through
        // CachedFrames::new gets one of these caps or the default, and renders the same bits.
        // cache_dir_from_env refuses what cache_limit_from_env refuses.
        std::env::set_var(CACHE_LIMIT_ENV, "1.5");
        assert_eq!(cache_limit_from_env(), Ok(1_500_000_000));
        std::env::set_var(CACHE_LIMIT_ENV, "");
        assert_eq!(cache_limit_from_env(), Ok(20_000_000_000));
        for bad in ["lots", "-1", "NaN"] {
            std::env::set_var(CACHE_LIMIT_ENV, bad);
            let e = cache_limit_from_env().unwrap_err();
            assert!(e.contains(CACHE_LIMIT_ENV) && e.contains(bad), "{e}");
            assert_eq!(cache_dir_from_env(), Err(e));
        }
        std::env::remove_var(CACHE_LIMIT_ENV);
        assert_eq!(cache_limit_from_env(), Ok(20_000_000_000));
    }

    #[test]
    fn the_key_follows_seed_and_configuration() {
        let gen = small("kinect");
        let key = generator_key(&gen);
        assert_eq!(key, generator_key(&gen.clone()));
        assert_ne!(key, generator_key(&Generator::new(gen.config().clone(), 4)));
        let mut cfg = gen.config().clone();
        cfg.image.noise_sigma += 1e-12;
        assert_ne!(key, generator_key(&Generator::new(cfg, 3)));
    }
}
