//! A real depth sensor's systematic errors, the ones bundle adjustment cannot average away
//! because they are the same in every frame (or, for quantisation, on the same lattice):
//!
//! - [`depth_distortion`]: z' = z (1 + L/100 (z / 3 m) F(u, v)), with F a smooth field over the
//!   image, |F| <= 1 and 1 at its extreme, drawn once per sequence: a multiplicative error that
//!   grows with range, L % at 3 m where it is largest (Teichman et al. RSS 2013; Herrera et al.
//!   2012).
//! - [`depth_registration`]: the depth at colour pixel p read at p + d(p), |d| = L px in a
//!   direction that varies smoothly (+-0.5 rad about one drawn once per sequence), nearest
//!   pixel; where a nearer surface (by more than 5 %) lies on the way from p to p + d, its depth
//!   wins, as a z-buffered registration lets the foreground cover the background: foreground
//!   edges grow by up to L px on the side the warp comes from.
//! - [`ir_shadow`]: the projector sits L x 7.5 cm to the right of the IR camera (+x of the image,
//!   the Kinect v1's layout seen from the sensor); a surface point it cannot see has no depth.
//!   Along a row, a point at column u and depth z falls at projector column u - f b / z; it is
//!   in shadow when a valid point to its right falls at a smaller projector column. A
//!   foreground edge facing away from the projector (a left edge) casts a hole on the
//!   background beside it, f b (1/z_fg - 1/z_bg) pixels wide; right edges cast none.
//! - [`disparity_quantization`]: depth measured as disparity d = f b / z at the Kinect's f b
//!   (43.5 px m: 7.5 cm x 580 px), rounded to a lattice of L/8 px after a jitter of half a step
//!   (sigma), as ICL-NUIM's simulator does (Handa et al. 2014), so the depth step grows as
//!   L z^2 / (8 f b): 2.9 mm at 1 m, 11.5 mm at 2 m at L = 1.
//!
//! Every output is on the depth PNG grid (`units` per metre); holes (0) stay holes.

use slam_core::{Camera, DepthImage};
use std::sync::{Arc, Mutex, OnceLock};
use synth::hash::{NoiseKey, Stream};
use synth::sensor::depth::quantise_png;

/// The Kinect v1's projector-to-IR-camera baseline, metres (Khoshelham & Elberink 2012).
pub const KINECT_BASELINE_M: f64 = 0.075;

/// The Kinect v1's IR focal length times its baseline, pixels x metres (580 px x 7.5 cm), the
/// scale of its disparity (synth's `DisparityQuantisation` default).
pub const KINECT_FB: f64 = 43.5;

/// The Kinect v1's disparity resolution, pixels (1/8 px).
pub const KINECT_DISPARITY_STEP: f64 = 0.125;

/// The noise stream a shared field is drawn from: depth-distortion's (range) or
/// depth-registration's (lateral).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldStream {
    /// `depth-distortion`.
    Range,
    /// `depth-registration`.
    Lateral,
}

/// Fields [`SmoothField::shared`] keeps (a sweep's chains hold a few systematic members).
pub const FIELD_CACHE: usize = 16;

/// A smooth field over a `w x h` image with values in [-1, 1] reaching +-1: a sum of six
/// separable cosines with periods between one and four image sizes, drawn from `key`.
/// Built as (row factors, column factors, normaliser), six products a pixel, and kept as the
/// value of every pixel: a field serves every frame of a sequence, so a frame reads it rather
/// than computing it again.
pub struct SmoothField {
    w: usize,
    values: Vec<f64>,
}

impl SmoothField {
    /// The field of `key` for a `w x h` image.
    pub fn new(key: NoiseKey, w: usize, h: usize) -> SmoothField {
        let mut cols = vec![[0.0; 6]; w];
        let mut rows = vec![[0.0; 6]; h];
        let tau = std::f64::consts::TAU;
        for k in 0..6 {
            let i = 8 * k as u64;
            let (px, py) = (
                w as f64 * (1.0 + 3.0 * key.uniform(i)),
                h as f64 * (1.0 + 3.0 * key.uniform(i + 1)),
            );
            let (fx, fy) = (tau * key.uniform(i + 2), tau * key.uniform(i + 3));
            let amp = 0.5 + key.uniform(i + 4);
            for (u, c) in cols.iter_mut().enumerate() {
                c[k] = amp * (tau * u as f64 / px + fx).cos();
            }
            for (v, r) in rows.iter_mut().enumerate() {
                r[k] = (tau * v as f64 / py + fy).cos();
            }
        }
        let mut values: Vec<f64> = (0..w * h)
            .map(|i| {
                let (c, r) = (&cols[i % w], &rows[i / w]);
                (0..6).map(|k| c[k] * r[k]).sum::<f64>()
            })
            .collect();
        let max = values.iter().fold(0.0f64, |m, s| m.max(s.abs()));
        let scale = if max > 0.0 { 1.0 / max } else { 0.0 };
        for s in &mut values {
            *s *= scale;
        }
        SmoothField { w, values }
    }

    /// The field of `key` for a `w x h` image, built once per process and shared: a
    /// systematic error's field is the same in every frame of a sequence (its member seed does
    /// not change from frame to frame), and building it costs a pass over the image. The last
    /// [`FIELD_CACHE`] fields are kept.
    pub fn shared(seed: u64, stream: FieldStream, w: usize, h: usize) -> Arc<SmoothField> {
        static CACHE: SharedCache<(u64, FieldStream, usize, usize), SmoothField> = OnceLock::new();
        shared(&CACHE, (seed, stream, w, h), FIELD_CACHE, || {
            let key = NoiseKey::new(
                seed,
                0,
                match stream {
                    FieldStream::Range => Stream::Range,
                    FieldStream::Lateral => Stream::Lateral,
                },
            );
            SmoothField::new(key, w, h)
        })
    }

    /// The field at pixel (u, v).
    #[inline]
    pub fn at(&self, u: usize, v: usize) -> f64 {
        self.values[v * self.w + u]
    }
}

/// A process-wide memo of values built once per key (what a sequence's fixed systematic
/// error needs in every frame), the last few kept.
type SharedCache<K, V> = OnceLock<Mutex<Vec<(K, Arc<V>)>>>;

/// The value of `key` in `cache`, built by `build` when it is not there (keeping at most
/// `keep` values, the oldest dropped first).
fn shared<K: PartialEq, V>(
    cache: &SharedCache<K, V>,
    key: K,
    keep: usize,
    build: impl FnOnce() -> V,
) -> Arc<V> {
    let cache = cache.get_or_init(Mutex::default);
    if let Some(v) = cache
        .lock()
        .ok()
        .and_then(|c| c.iter().find(|(k, _)| *k == key).map(|(_, v)| v.clone()))
    {
        return v;
    }
    let value = Arc::new(build());
    if let Ok(mut c) = cache.lock() {
        if c.len() >= keep {
            c.remove(0);
        }
        c.push((key, value.clone()));
    }
    value
}

/// `depth-distortion` at `level` percent at 3 m, field drawn from member seed `seed`.
pub fn depth_distortion(depth: &DepthImage, level: f64, units: f64, seed: u64) -> DepthImage {
    let (w, h) = (depth.width, depth.height);
    let field = SmoothField::shared(seed, FieldStream::Range, w, h);
    let k = level / 100.0 / 3.0;
    map_valid(depth, |i, z| {
        quantise_png(z * (1.0 + k * z * field.at(i % w, i / w)), units)
    })
}

/// `depth` with every valid pixel (index, metres) mapped by `f`; holes stay holes.
pub(crate) fn map_valid(depth: &DepthImage, f: impl Fn(usize, f64) -> f32) -> DepthImage {
    DepthImage {
        width: depth.width,
        height: depth.height,
        data: depth
            .data
            .iter()
            .enumerate()
            .map(|(i, &z)| if z <= 0.0 { z } else { f(i, z as f64) })
            .collect(),
    }
}

/// The displacement (pixels) of `depth-registration` at `level` at pixel (u, v), for the
/// field and base direction of member seed `seed` (see [`depth_registration`]).
pub struct RegistrationWarp {
    field: Arc<SmoothField>,
    base: f64,
    level: f64,
}

impl RegistrationWarp {
    /// The warp of `level` pixels for a `w x h` image and member seed `seed`.
    pub fn new(level: f64, seed: u64, w: usize, h: usize) -> RegistrationWarp {
        RegistrationWarp {
            field: SmoothField::shared(seed, FieldStream::Lateral, w, h),
            base: NoiseKey::new(seed, 1, Stream::Lateral).uniform(0) * std::f64::consts::TAU,
            level,
        }
    }

    /// The displacement at (u, v), pixels.
    pub fn at(&self, u: usize, v: usize) -> (f64, f64) {
        let a = self.base + 0.5 * self.field.at(u, v);
        (self.level * a.cos(), self.level * a.sin())
    }
}

/// Where `depth-registration` reads each pixel from, for one level, member seed and image
/// size: the pixel at the end of its warp and the pixels on the way there, each the nearest
/// pixel of its point (the same in every frame of a sequence, so built once; see
/// [`RegistrationTable::shared`]).
pub struct RegistrationTable {
    /// Points on the way from a pixel to its warped position (`ceil(level)`, at least 1).
    steps: usize,
    /// Per pixel, the index read at the warp's end ([`OUTSIDE`] off the image).
    end: Vec<u32>,
    /// Per pixel, `steps` indices on the way, the pixel itself first ([`OUTSIDE`] off the image).
    way: Vec<u32>,
}

/// A point that falls off the image.
const OUTSIDE: u32 = u32::MAX;

/// Registration tables [`RegistrationTable::shared`] keeps (one per run in flight).
const TABLE_CACHE: usize = 4;

impl RegistrationTable {
    /// The table of `level` pixels for a `w x h` image and member seed `seed`.
    pub fn new(level: f64, seed: u64, w: usize, h: usize) -> RegistrationTable {
        let warp = RegistrationWarp::new(level, seed, w, h);
        let index = |x: f64, y: f64| -> u32 {
            let (x, y) = (x.round(), y.round());
            if x < 0.0 || y < 0.0 || x >= w as f64 || y >= h as f64 {
                return OUTSIDE;
            }
            (y as usize * w + x as usize) as u32
        };
        let steps = level.ceil().max(1.0) as usize;
        let mut end = Vec::with_capacity(w * h);
        let mut way = Vec::with_capacity(w * h * steps);
        for i in 0..w * h {
            let (u, v) = (i % w, i / w);
            let (dx, dy) = warp.at(u, v);
            end.push(index(u as f64 + dx, v as f64 + dy));
            for s in 0..steps {
                let t = s as f64 / steps as f64;
                way.push(index(u as f64 + t * dx, v as f64 + t * dy));
            }
        }
        RegistrationTable { steps, end, way }
    }

    /// The table of `level`, `seed` and size, built once per process and shared by every frame
    /// (the last [`TABLE_CACHE`] kept).
    pub fn shared(level: f64, seed: u64, w: usize, h: usize) -> Arc<RegistrationTable> {
        static CACHE: SharedCache<(u64, u64, usize, usize), RegistrationTable> = OnceLock::new();
        shared(&CACHE, (level.to_bits(), seed, w, h), TABLE_CACHE, || {
            RegistrationTable::new(level, seed, w, h)
        })
    }
}

/// `depth-registration` at `level` pixels, warp drawn from member seed `seed`.
pub fn depth_registration(depth: &DepthImage, level: f64, seed: u64) -> DepthImage {
    let (w, h) = (depth.width, depth.height);
    let table = RegistrationTable::shared(level, seed, w, h);
    let src = &depth.data;
    let data = table
        .end
        .iter()
        .zip(table.way.chunks_exact(table.steps))
        .map(|(&end, way)| {
            if end == OUTSIDE {
                return 0.0;
            }
            // The nearest surface on the way, where it is a different (nearer) one.
            let mut best = src[end as usize];
            for &p in way.iter().filter(|&&p| p != OUTSIDE) {
                let zs = src[p as usize];
                if zs > 0.0 && (best <= 0.0 || (zs as f64) < 0.95 * best as f64) {
                    best = zs;
                }
            }
            best
        })
        .collect();
    DepthImage {
        width: w,
        height: h,
        data,
    }
}

/// `ir-shadow` at `level` x the Kinect's baseline, for a camera of focal length `camera.fx`.
pub fn ir_shadow(depth: &DepthImage, level: f64, camera: &Camera) -> DepthImage {
    let (w, h) = (depth.width, depth.height);
    let fb = camera.fx * KINECT_BASELINE_M * level;
    let mut data = depth.data.clone();
    for v in 0..h {
        let row = &depth.data[v * w..(v + 1) * w];
        let mut min_right = f64::INFINITY;
        for u in (0..w).rev() {
            let z = row[u] as f64;
            if z <= 0.0 {
                continue;
            }
            let up = u as f64 - fb / z;
            if up > min_right {
                data[v * w + u] = 0.0;
            } else {
                min_right = up;
            }
        }
    }
    DepthImage {
        width: w,
        height: h,
        data,
    }
}

/// `disparity-quantization` at `level` x 1/8 px: frame `frame`'s jitter drawn from member seed
/// `seed`.
pub fn disparity_quantization(
    depth: &DepthImage,
    level: f64,
    units: f64,
    seed: u64,
    frame: usize,
) -> DepthImage {
    let key = NoiseKey::new(seed, frame, Stream::Axial);
    let step = level * KINECT_DISPARITY_STEP;
    map_valid(depth, |i, z| {
        let d = KINECT_FB / z / step + 0.5 * key.normal(i as u64);
        let k = d.round().max(1.0);
        quantise_png(KINECT_FB / (k * step), units)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smooth_field_reaches_one_and_varies_slowly() {
        let f = SmoothField::new(NoiseKey::new(5, 0, Stream::Range), 640, 480);
        let mut max = 0.0f64;
        let mut step = 0.0f64;
        for v in 0..480 {
            for u in 0..640 {
                let a = f.at(u, v);
                assert!(a.abs() <= 1.0 + 1e-12);
                max = max.max(a.abs());
                if u > 0 {
                    step = step.max((a - f.at(u - 1, v)).abs());
                }
            }
        }
        assert!((max - 1.0).abs() < 1e-12, "{max}");
        // Periods of at least an image width: a pixel moves it by at most 6 x 1.5 x 2 pi / 640
        // before normalisation.
        assert!(step < 0.2, "{step}");
    }
}

#[cfg(test)]
mod shared_field_tests {
    use super::*;

    /// `depth-registration` as defined, every point's nearest pixel found per frame: what the
    /// table must reproduce bit for bit.
    fn registration_by_definition(depth: &DepthImage, level: f64, seed: u64) -> DepthImage {
        let (w, h) = (depth.width, depth.height);
        let warp = RegistrationWarp::new(level, seed, w, h);
        let src = &depth.data;
        let sample = |x: f64, y: f64| -> Option<f32> {
            let (x, y) = (x.round(), y.round());
            if x < 0.0 || y < 0.0 || x >= w as f64 || y >= h as f64 {
                return None;
            }
            Some(src[y as usize * w + x as usize])
        };
        let steps = level.ceil().max(1.0) as usize;
        let data = (0..w * h)
            .map(|i| {
                let (u, v) = (i % w, i / w);
                let (dx, dy) = warp.at(u, v);
                let Some(z) = sample(u as f64 + dx, v as f64 + dy) else {
                    return 0.0;
                };
                let mut best = z;
                for s in 0..steps {
                    let t = s as f64 / steps as f64;
                    if let Some(zs) = sample(u as f64 + t * dx, v as f64 + t * dy) {
                        if zs > 0.0 && (best <= 0.0 || (zs as f64) < 0.95 * best as f64) {
                            best = zs;
                        }
                    }
                }
                best
            })
            .collect();
        DepthImage {
            width: w,
            height: h,
            data,
        }
    }

    #[test]
    fn registration_through_its_table_is_the_definition_bit_for_bit() {
        let (w, h) = (97, 61);
        // Steps, slopes and holes, so the nearer-surface rule and the image border both act.
        let data = (0..w * h)
            .map(|i| {
                let (u, v) = (i % w, i / w);
                match (u * 7 + v * 3) % 23 {
                    0 | 1 => 0.0,
                    k if u > w / 2 => 1.0 + 0.013 * k as f32 + 0.002 * v as f32,
                    k => 2.5 - 0.011 * k as f32,
                }
            })
            .collect();
        let depth = DepthImage {
            width: w,
            height: h,
            data,
        };
        for (level, seed) in [(0.3, 1), (1.0, 2), (2.5, 3), (6.0, 4), (13.7, 5)] {
            let table = depth_registration(&depth, level, seed);
            let direct = registration_by_definition(&depth, level, seed);
            let bits = |d: &DepthImage| d.data.iter().map(|z| z.to_bits()).collect::<Vec<_>>();
            let differ = |a: &DepthImage, b: &DepthImage| bits(a) != bits(b);
            assert!(!differ(&table, &direct), "level {level}");
            // Below half a pixel nothing moves; from a pixel on the warp does.
            assert_eq!(differ(&table, &depth), level >= 1.0, "level {level}");
            // Again from the shared table: the same.
            assert!(!differ(&depth_registration(&depth, level, seed), &direct));
        }
    }

    #[test]
    fn a_stored_field_is_its_sum_of_cosines() {
        // The definition, written out: six separable cosines drawn from the key, divided by
        // the largest magnitude over the image.
        let (w, h) = (40, 30);
        let key = NoiseKey::new(3, 0, Stream::Range);
        let tau = std::f64::consts::TAU;
        let raw = |u: usize, v: usize| -> f64 {
            (0..6)
                .map(|k| {
                    let i = 8 * k as u64;
                    let px = w as f64 * (1.0 + 3.0 * key.uniform(i));
                    let py = h as f64 * (1.0 + 3.0 * key.uniform(i + 1));
                    let (fx, fy) = (tau * key.uniform(i + 2), tau * key.uniform(i + 3));
                    let amp = 0.5 + key.uniform(i + 4);
                    amp * (tau * u as f64 / px + fx).cos() * (tau * v as f64 / py + fy).cos()
                })
                .sum::<f64>()
        };
        let max = (0..w * h).fold(0.0f64, |m, i| m.max(raw(i % w, i / w).abs()));
        let f = SmoothField::new(key, w, h);
        for (u, v) in [(0, 0), (17, 3), (39, 29), (5, 22)] {
            assert_eq!(f.at(u, v).to_bits(), (raw(u, v) * (1.0 / max)).to_bits());
        }
    }

    #[test]
    fn a_shared_field_is_the_field_built_afresh() {
        let fresh = SmoothField::new(NoiseKey::new(9, 0, Stream::Lateral), 64, 48);
        let a = SmoothField::shared(9, FieldStream::Lateral, 64, 48);
        let b = SmoothField::shared(9, FieldStream::Lateral, 64, 48);
        assert!(Arc::ptr_eq(&a, &b), "built once");
        let other = SmoothField::shared(9, FieldStream::Range, 64, 48);
        for (u, v) in [(0, 0), (13, 7), (63, 47)] {
            assert_eq!(a.at(u, v).to_bits(), fresh.at(u, v).to_bits());
        }
        assert_ne!(other.at(13, 7), a.at(13, 7));
    }
}
