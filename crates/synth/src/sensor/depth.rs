//! The depth-sensor model (after Nguyen et al. 2012, the paper's ref \[31\]): its components,
//! each its own switch ([`DepthNoise`]), and how they turn a true depth image into a measured one.
//!
//! For each output pixel, in this order: misregistration and lateral noise choose the source
//! pixel whose true depth is measured; holes drop it (range, grazing incidence, boundaries);
//! systematic distortion scales it; axial noise is added; disparity quantisation rounds it;
//! finally it is rounded to the TUM PNG resolution (1/5000 m) so that memory and disk agree.
//! Every random number is a hash of (seed, frame, stream, pixel): see [`crate::hash`].

use rayon::prelude::*;
use slam_core::Camera;

use crate::hash::{NoiseKey, Stream};

/// TUM depth PNG scale: one unit is 1/5000 m.
pub const DEPTH_FACTOR: f64 = 5000.0;

/// Axial noise after Nguyen et al. 2012: sigma_z(z, theta) = a + b (z - z0)^2 metres, plus
/// (when `grazing` is on) 0.0001 / sqrt(z) * theta^2 / (pi/2 - theta)^2 for incidence theta.
#[derive(Clone, Debug, PartialEq)]
pub struct AxialNoise {
    /// Constant term `a`, metres (default 0.0012).
    pub a: f64,
    /// Quadratic coefficient `b`, 1/metre (default 0.0019).
    pub b: f64,
    /// Depth of the minimum, metres (default 0.4).
    pub z0: f64,
    /// Add Nguyen's grazing-angle term (default true).
    pub grazing: bool,
}

impl Default for AxialNoise {
    fn default() -> Self {
        AxialNoise {
            a: 0.0012,
            b: 0.0019,
            z0: 0.4,
            grazing: true,
        }
    }
}

impl AxialNoise {
    /// Standard deviation in metres at depth `z` (metres) and incidence angle `theta` (radians).
    pub fn sigma(&self, z: f64, theta: f64) -> f64 {
        let mut s = self.a + self.b * (z - self.z0).powi(2);
        if self.grazing {
            let t = theta.clamp(0.0, std::f64::consts::FRAC_PI_2 - 1e-3);
            s += 0.0001 / z.max(1e-3).sqrt() * t * t / (std::f64::consts::FRAC_PI_2 - t).powi(2);
        }
        s
    }
}

/// Disparity quantisation of a structured-light sensor: depth is measured as disparity
/// d = bf / z rounded to 1/`subpixel` pixel, then converted back.
#[derive(Clone, Debug, PartialEq)]
pub struct DisparityQuantisation {
    /// Projector-camera baseline times focal length, metres * pixels (Kinect v1: 0.075 m * 580 px = 43.5).
    pub bf: f64,
    /// Disparity sub-pixel resolution, steps per pixel (Kinect v1: 8).
    pub subpixel: f64,
}

impl Default for DisparityQuantisation {
    fn default() -> Self {
        DisparityQuantisation {
            bf: 43.5,
            subpixel: 8.0,
        }
    }
}

/// Lateral noise: a pixel's depth is taken from the neighbour at an offset of
/// (round N(0, sigma), round N(0, sigma)) pixels, which mixes fore- and background at boundaries.
#[derive(Clone, Debug, PartialEq)]
pub struct LateralNoise {
    /// Standard deviation of the offset, pixels (default 0.8).
    pub sigma_px: f64,
}

impl Default for LateralNoise {
    fn default() -> Self {
        LateralNoise { sigma_px: 0.8 }
    }
}

/// Where the sensor returns no depth (value 0).
#[derive(Clone, Debug, PartialEq)]
pub struct Holes {
    /// Minimum range, metres (default 0.4).
    pub min_range: f64,
    /// Maximum range where every pixel still has depth, metres (default 4.0).
    pub max_range: f64,
    /// The per-pixel cut-off is uniform in [max_range, max_range + max_range_spread] (default 1.0 m).
    pub max_range_spread: f64,
    /// Incidence angle beyond which no depth is returned, degrees (default 78).
    pub max_incidence_deg: f64,
    /// Probability of a hole at a depth-boundary pixel (default 0.35).
    pub boundary_probability: f64,
    /// A pixel is on a boundary when a 4-neighbour's depth differs by more than this fraction
    /// of its own depth (default 0.05).
    pub boundary_jump: f64,
}

impl Default for Holes {
    fn default() -> Self {
        Holes {
            min_range: 0.4,
            max_range: 4.0,
            max_range_spread: 1.0,
            max_incidence_deg: 78.0,
            boundary_probability: 0.35,
            boundary_jump: 0.05,
        }
    }
}

/// RGB-to-depth misregistration: the depth at RGB pixel (u, v) is the sensor's depth at
/// (u + dx, v + dy) (nearest pixel).
#[derive(Clone, Debug, PartialEq)]
pub struct Misregistration {
    /// Horizontal shift, pixels (preset `boundary`: 4).
    pub dx_px: f64,
    /// Vertical shift, pixels (preset `boundary`: 1).
    pub dy_px: f64,
}

/// Depth time lag (as fr2's depth / colour offset, or an unsynchronised sensor): the depth image
/// is rendered from the camera pose and scene `frames` frames earlier, but stamped as the colour.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthLag {
    /// Lag in frames, may be fractional (preset `lag`: 2).
    pub frames: f64,
}

/// Systematic depth distortion of a miscalibrated sensor: z' = z (1 + scale_error +
/// wobble_amplitude * (r / r_max)^2 * cos(2 pi r / wobble_period_px)), r = distance from the
/// image centre in pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct SystematicDistortion {
    /// Relative depth scale error (preset `distorted`: 0.04, i.e. +4 %).
    pub scale_error: f64,
    /// Relative amplitude of the radial wobble at the image corner (preset: 0.015).
    pub wobble_amplitude: f64,
    /// Radial period of the wobble, pixels (preset: 180).
    pub wobble_period_px: f64,
}

impl Default for SystematicDistortion {
    fn default() -> Self {
        SystematicDistortion {
            scale_error: 0.04,
            wobble_amplitude: 0.015,
            wobble_period_px: 180.0,
        }
    }
}

/// The depth-sensor model (RGB-D only). `None` switches a component off.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DepthNoise {
    /// Random axial noise.
    pub axial: Option<AxialNoise>,
    /// Disparity quantisation.
    pub quantisation: Option<DisparityQuantisation>,
    /// Lateral (neighbour-mixing) noise.
    pub lateral: Option<LateralNoise>,
    /// Missing depth.
    pub holes: Option<Holes>,
    /// RGB-depth misregistration.
    pub misregistration: Option<Misregistration>,
    /// Depth time lag.
    pub lag: Option<DepthLag>,
    /// Systematic (calibration) distortion.
    pub distortion: Option<SystematicDistortion>,
}

impl DepthNoise {
    /// The Kinect-like model: axial + quantisation + lateral + holes, all at their defaults.
    pub fn kinect() -> Self {
        DepthNoise {
            axial: Some(AxialNoise::default()),
            quantisation: Some(DisparityQuantisation::default()),
            lateral: Some(LateralNoise::default()),
            holes: Some(Holes::default()),
            ..DepthNoise::default()
        }
    }
}

/// Rounds half away from zero to an integer (an inline conversion: `f64::round` is a libm call
/// on baseline x86-64).
#[inline]
fn iround(x: f64) -> i64 {
    if x >= 0.0 {
        (x + 0.5) as i64
    } else {
        (x - 0.5) as i64
    }
}

/// Rounds metres to the resolution of a 16-bit depth PNG of `units` per metre; 0 stays 0
/// (invalid), out-of-range becomes 0.
#[inline]
pub fn quantise_png(z: f64, units: f64) -> f32 {
    let q = iround(z * units) as f64;
    if !(1.0..=65535.0).contains(&q) {
        return 0.0;
    }
    (q / units) as f32
}

/// Applies the sensor model to a true depth image (`depth`, `cos_incidence` of the pixel-centre
/// rays, row-major `width x height`) and returns the measured depth in metres (0 = hole), on
/// the grid of a 16-bit PNG of `units` per metre.
pub fn sensor_depth(
    model: &DepthNoise,
    units: f64,
    camera: &Camera,
    depth: &[f32],
    cos_incidence: &[f32],
    seed: u64,
    frame: usize,
) -> Vec<f32> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let k_axial = NoiseKey::new(seed, frame, Stream::Axial);
    let k_lat = NoiseKey::new(seed, frame, Stream::Lateral);
    let k_bnd = NoiseKey::new(seed, frame, Stream::BoundaryHole);
    let k_rng = NoiseKey::new(seed, frame, Stream::Range);
    let (mdx, mdy) = model
        .misregistration
        .as_ref()
        .map_or((0, 0), |m| (m.dx_px.round() as i64, m.dy_px.round() as i64));
    let r_max = (camera.cx.max(w as f64 - camera.cx).powi(2)
        + camera.cy.max(h as f64 - camera.cy).powi(2))
    .sqrt();
    // The measured depth of each disparity step below QUANTISED_STEPS (entry 0 unused).
    let quantised: Vec<f32> = match &model.quantisation {
        Some(q) => (0..QUANTISED_STEPS)
            .map(|k| quantise_png(disparity_depth(q, k.max(1) as i64), units))
            .collect(),
        None => Vec::new(),
    };
    let is_boundary = |x: usize, y: usize, jump: f64| -> bool {
        let z = depth[y * w + x] as f64;
        let lim = jump * z;
        let mut b = false;
        if x > 0 {
            b |= (depth[y * w + x - 1] as f64 - z).abs() > lim;
        }
        if x + 1 < w {
            b |= (depth[y * w + x + 1] as f64 - z).abs() > lim;
        }
        if y > 0 {
            b |= (depth[(y - 1) * w + x] as f64 - z).abs() > lim;
        }
        if y + 1 < h {
            b |= (depth[(y + 1) * w + x] as f64 - z).abs() > lim;
        }
        b
    };
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (u, v) = ((i % w) as i64, (i / w) as i64);
            let (mut su, mut sv) = (u + mdx, v + mdy);
            if let Some(l) = &model.lateral {
                let (a, b) = k_lat.normal2(i as u64);
                su = (su + iround(a * l.sigma_px)).clamp(0, w as i64 - 1);
                sv = (sv + iround(b * l.sigma_px)).clamp(0, h as i64 - 1);
            }
            if su < 0 || sv < 0 || su >= w as i64 || sv >= h as i64 {
                return 0.0;
            }
            let (su, sv) = (su as usize, sv as usize);
            let s = sv * w + su;
            let z_true = depth[s] as f64;
            if !(z_true.is_finite() && z_true > 0.0) {
                return 0.0;
            }
            // The incidence angle only when a component uses it (an acos per pixel otherwise),
            // and once.
            let mut theta_once = None;
            let mut theta = || {
                *theta_once.get_or_insert_with(|| (cos_incidence[s] as f64).clamp(0.0, 1.0).acos())
            };
            if let Some(hl) = &model.holes {
                let cut = hl.max_range + hl.max_range_spread * k_rng.uniform(i as u64);
                if z_true < hl.min_range
                    || z_true > cut
                    || theta() > hl.max_incidence_deg.to_radians()
                    || (hl.boundary_probability > 0.0
                        && is_boundary(su, sv, hl.boundary_jump)
                        && k_bnd.uniform(i as u64) < hl.boundary_probability)
                {
                    return 0.0;
                }
            }
            let mut z = z_true;
            if let Some(d) = &model.distortion {
                let r = ((u as f64 - camera.cx).powi(2) + (v as f64 - camera.cy).powi(2)).sqrt();
                let wob = d.wobble_amplitude
                    * (r / r_max).powi(2)
                    * (std::f64::consts::TAU * r / d.wobble_period_px).cos();
                z *= 1.0 + d.scale_error + wob;
            }
            if let Some(a) = &model.axial {
                let t = if a.grazing { theta() } else { 0.0 };
                z += a.sigma(z_true, t) * k_axial.normal(i as u64);
            }
            if let Some(q) = &model.quantisation {
                let disparity = q.bf / z.max(1e-3);
                let step = iround(disparity * q.subpixel).max(1);
                // What the steps give, quantised: looked up for the usual disparities.
                if let Some(&v) = quantised.get(step as usize) {
                    return v;
                }
                z = disparity_depth(q, step);
            }
            quantise_png(z, units)
        })
        .collect()
}

/// Disparity steps below this have their quantised depth tabulated per frame (1024 steps of
/// 1/8 px: 128 px, depth down to 0.34 m for the Kinect's 43.5 m px).
const QUANTISED_STEPS: usize = 1024;

/// The depth of `step` (>= 1) disparity steps of `q`.
#[inline]
fn disparity_depth(q: &DisparityQuantisation, step: i64) -> f64 {
    let dq = (step as f64).max(1.0) / q.subpixel;
    q.bf / dq
}

/// Depth lost in blobs, as structured-light and time-of-flight sensors lose it (dark or
/// specular patches, interference): discs of random centre and radius are removed one after
/// another until `share` of the image's valid pixels is gone. Applied to a measured depth
/// image (the perturbation layer's `depth-holes`).
#[derive(Clone, Debug, PartialEq)]
pub struct BlobHoles {
    /// Share of the valid depth pixels to remove, in [0, 1).
    pub share: f64,
    /// Smallest and largest blob radius, pixels (default 3 to 14 at 640x480).
    pub radius_px: (f64, f64),
}

impl BlobHoles {
    /// Removes blobs from `depth` (`width x height`, metres, 0 = hole) until exactly
    /// `round(share * valid)` more pixels are holes; every draw is a hash of `key`.
    pub fn apply(&self, depth: &mut [f32], width: usize, height: usize, key: NoiseKey) {
        let valid = depth.iter().filter(|&&z| z > 0.0).count();
        let target = (self.share.clamp(0.0, 1.0) * valid as f64).round() as usize;
        let mut removed = 0usize;
        let mut blob = 0u64;
        // A blob draws 3 numbers; stop also when the image has nothing left to remove.
        while removed < target && blob < 64 * (width * height) as u64 {
            let cx = key.uniform(3 * blob) * width as f64;
            let cy = key.uniform(3 * blob + 1) * height as f64;
            let (r0, r1) = self.radius_px;
            let r = r0 + (r1 - r0) * key.uniform(3 * blob + 2);
            blob += 1;
            let (x0, x1) = ((cx - r).floor().max(0.0) as usize, (cx + r).ceil() as usize);
            let (y0, y1) = ((cy - r).floor().max(0.0) as usize, (cy + r).ceil() as usize);
            for y in y0..y1.min(height) {
                for x in x0..x1.min(width) {
                    let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
                    let z = &mut depth[y * width + x];
                    if dx * dx + dy * dy <= r * r && *z > 0.0 {
                        *z = 0.0;
                        removed += 1;
                        if removed == target {
                            return;
                        }
                    }
                }
            }
        }
    }
}

/// Flying pixels: at a depth discontinuity a time-of-flight or structured-light pixel that sees
/// both surfaces returns a depth between them. Every valid pixel within `band_px` pixels
/// (Chebyshev distance) of a jump larger than `jump` of its depth takes a depth drawn
/// uniformly between the nearest and the farthest valid depth within `band_px` of it.
#[derive(Clone, Debug, PartialEq)]
pub struct FlyingPixels {
    /// Half-width of the band around a discontinuity, pixels.
    pub band_px: usize,
    /// Relative depth difference between 4-neighbours that makes a discontinuity (default 0.05,
    /// as [`Holes::boundary_jump`]).
    pub jump: f64,
}

impl FlyingPixels {
    /// Returns `depth` with flying pixels (rounded to the PNG grid of `units` per metre); pixels
    /// away from discontinuities keep their bytes.
    pub fn apply(
        &self,
        depth: &[f32],
        width: usize,
        height: usize,
        units: f64,
        key: NoiseKey,
    ) -> Vec<f32> {
        let (w, h) = (width, height);
        let at = |x: usize, y: usize| depth[y * w + x];
        // Discontinuity pixels: a valid 4-neighbour whose depth differs by more than `jump`.
        let mut edge = vec![false; w * h];
        for y in 0..h {
            for x in 0..w {
                let z = at(x, y);
                if z <= 0.0 {
                    continue;
                }
                let lim = self.jump as f32 * z;
                let mut e = false;
                for (nx, ny) in [
                    (x.wrapping_sub(1), y),
                    (x + 1, y),
                    (x, y.wrapping_sub(1)),
                    (x, y + 1),
                ] {
                    if nx < w && ny < h {
                        let n = at(nx, ny);
                        e |= n > 0.0 && (n - z).abs() > lim;
                    }
                }
                edge[y * w + x] = e;
            }
        }
        // Dilate by band_px - 1 (a band of 1 is the discontinuity pixels themselves).
        let mut band = edge.clone();
        let r = self.band_px.saturating_sub(1);
        if r > 0 {
            let mut rows = vec![false; w * h];
            for y in 0..h {
                for x in 0..w {
                    let (a, b) = (x.saturating_sub(r), (x + r).min(w - 1));
                    rows[y * w + x] = (a..=b).any(|k| edge[y * w + k]);
                }
            }
            for y in 0..h {
                for x in 0..w {
                    let (a, b) = (y.saturating_sub(r), (y + r).min(h - 1));
                    band[y * w + x] = (a..=b).any(|k| rows[k * w + x]);
                }
            }
        }
        (0..w * h)
            .into_par_iter()
            .map(|i| {
                let z = depth[i];
                if !band[i] || z <= 0.0 || self.band_px == 0 {
                    return z;
                }
                let (x, y) = (i % w, i / w);
                let r = self.band_px;
                let (mut lo, mut hi) = (f32::INFINITY, 0f32);
                for ny in y.saturating_sub(r)..=(y + r).min(h - 1) {
                    for nx in x.saturating_sub(r)..=(x + r).min(w - 1) {
                        let n = at(nx, ny);
                        if n > 0.0 {
                            lo = lo.min(n);
                            hi = hi.max(n);
                        }
                    }
                }
                if hi <= lo {
                    return z;
                }
                let t = key.uniform(i as u64);
                quantise_png(lo as f64 + t * (hi - lo) as f64, units)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(z: f32) -> (Camera, Vec<f32>, Vec<f32>) {
        let cam = Camera::tum_fr3();
        let n = (cam.width * cam.height) as usize;
        (cam, vec![z; n], vec![1.0; n])
    }

    /// Measured axial noise std on a fronto-parallel plane at 1, 2, 3 m is within 10 % of
    /// Nguyen's sigma_z(z).
    #[test]
    fn axial_noise_std_matches_model_at_1_2_3_m() {
        let axial = AxialNoise::default();
        let model = DepthNoise {
            axial: Some(axial.clone()),
            ..DepthNoise::default()
        };
        for z in [1.0f32, 2.0, 3.0] {
            let (cam, d, c) = flat(z);
            let out = sensor_depth(&model, DEPTH_FACTOR, &cam, &d, &c, 11, 4);
            let n = out.len() as f64;
            let mean = out.iter().map(|&x| x as f64).sum::<f64>() / n;
            let var = out.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / n;
            let want = axial.sigma(z as f64, 0.0);
            let got = var.sqrt();
            assert!(
                (got / want - 1.0).abs() < 0.10,
                "z {z}: std {got} vs model {want}"
            );
            assert!(
                (mean - z as f64).abs() < 3.0 * want / n.sqrt() + 1e-4,
                "unbiased at {z}"
            );
        }
    }

    #[test]
    fn quantisation_gives_disparity_steps() {
        let model = DepthNoise {
            quantisation: Some(DisparityQuantisation::default()),
            ..DepthNoise::default()
        };
        let (cam, _, c) = flat(3.0);
        let d: Vec<f32> = (0..c.len())
            .map(|i| 2.9 + 0.2 * (i as f32 / c.len() as f32))
            .collect();
        let out = sensor_depth(&model, DEPTH_FACTOR, &cam, &d, &c, 1, 0);
        let mut levels: Vec<u32> = out.iter().map(|&z| (z * 5000.0).round() as u32).collect();
        levels.dedup();
        levels.sort();
        levels.dedup();
        // 2.9..3.1 m spans 0.125 px steps of 43.5/z: about 8 distinct depths.
        assert!(
            levels.len() >= 6 && levels.len() <= 10,
            "{} levels",
            levels.len()
        );
    }

    #[test]
    fn holes_out_of_range_and_at_grazing_angles() {
        let model = DepthNoise {
            holes: Some(Holes {
                boundary_probability: 0.0,
                ..Holes::default()
            }),
            ..DepthNoise::default()
        };
        let (cam, mut d, mut c) = flat(2.0);
        d[0] = 0.3;
        d[1] = 5.1;
        c[2] = 80f32.to_radians().cos();
        let out = sensor_depth(&model, DEPTH_FACTOR, &cam, &d, &c, 1, 0);
        assert_eq!(&out[..4], &[0.0, 0.0, 0.0, 2.0]);
        assert!(out[3..].iter().all(|&z| z == 2.0));
    }

    #[test]
    fn lateral_noise_is_a_no_op_on_constant_depth() {
        let model = DepthNoise {
            lateral: Some(LateralNoise { sigma_px: 2.0 }),
            ..DepthNoise::default()
        };
        let (cam, d, c) = flat(1.5);
        let out = sensor_depth(&model, DEPTH_FACTOR, &cam, &d, &c, 1, 0);
        assert!(out.iter().all(|&z| z == 1.5));
    }

    #[test]
    fn axial_sigma_matches_nguyen() {
        let a = AxialNoise {
            grazing: false,
            ..AxialNoise::default()
        };
        assert!((a.sigma(1.0, 0.0) - (0.0012 + 0.0019 * 0.36)).abs() < 1e-12);
        let g = AxialNoise::default();
        assert!(g.sigma(2.0, 1.3) > a.sigma(2.0, 1.3) + 0.001);
    }
}
