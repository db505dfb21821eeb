//! The depth-sensor model (after Nguyen et al. 2012, the paper's ref [31]) and the image noise.
//!
//! For each output pixel, in this order: misregistration and lateral noise choose the source
//! pixel whose true depth is measured; holes drop it (range, grazing incidence, boundaries);
//! systematic distortion scales it; axial noise is added; disparity quantisation rounds it;
//! finally it is rounded to the TUM PNG resolution (1/5000 m) so that memory and disk agree.
//! Every random number is a hash of (seed, frame, stream, pixel): see [`crate::hash`].

use rayon::prelude::*;
use slam_core::Camera;

use crate::config::DepthNoise;
use crate::hash::{NoiseKey, Stream};

/// TUM depth PNG scale: one unit is 1/5000 m.
pub const DEPTH_FACTOR: f64 = 5000.0;

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

/// Rounds to the nearest grey level and clamps to 0..=255 (cheaper than `f64::round`).
#[inline]
fn grey_level(v: f64) -> u8 {
    (v + 0.5).clamp(0.0, 255.0) as u8
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
            let theta = (cos_incidence[s] as f64).clamp(0.0, 1.0).acos();
            if let Some(hl) = &model.holes {
                let cut = hl.max_range + hl.max_range_spread * k_rng.uniform(i as u64);
                if z_true < hl.min_range
                    || z_true > cut
                    || theta > hl.max_incidence_deg.to_radians()
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
                z += a.sigma(z_true, theta) * k_axial.normal(i as u64);
            }
            if let Some(q) = &model.quantisation {
                let disparity = q.bf / z.max(1e-3);
                let dq = (iround(disparity * q.subpixel) as f64).max(1.0) / q.subpixel;
                z = q.bf / dq;
            }
            quantise_png(z, units)
        })
        .collect()
}

/// Adds Gaussian grey-level noise (sigma in grey levels) to linear colour and rounds to RGB8.
pub fn noisy_rgb8(colour: &[[f32; 3]], sigma: f64, key: NoiseKey) -> Vec<u8> {
    colour
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, c)| {
            let (n0, n1) = key.normal2(2 * i as u64);
            let n2 = key.normal(2 * i as u64 + 1);
            let n = [n0, n1, n2];
            (0..3).map(move |k| grey_level(c[k] as f64 + sigma * n[k]))
        })
        .collect()
}

/// The photometric chain of a real sensor, for [`exposed_rgb8`] and [`exposed_gray8`]: radiance
/// times the exposure scale and the vignetting, plus shot and read noise (or the constant
/// `sigma` when the sensor noise is off), rounded and clipped to 8 bits.
pub struct Photometry<'a> {
    /// Image size and principal point (for vignetting).
    pub camera: &'a Camera,
    /// Multiplier of the radiance (auto-exposure; 1 without).
    pub scale: f64,
    /// Analogue gain (amplifies the sensor noise).
    pub gain: f64,
    /// Vignetting, if on.
    pub vignetting: Option<&'a crate::imaging::Vignetting>,
    /// Shot and read noise, if on.
    pub sensor: Option<&'a crate::imaging::SensorNoise>,
    /// Constant grey-level sigma used when `sensor` is off.
    pub sigma: f64,
}

impl Photometry<'_> {
    /// The noise-free level of radiance `c` under vignetting `vig`, and its noise sigma.
    #[inline]
    fn level(&self, c: f64, vig: f64) -> (f64, f64) {
        let level = c * self.scale * vig;
        let sigma = match self.sensor {
            Some(s) => s.sigma(level, self.gain),
            None => self.sigma,
        };
        (level, sigma)
    }

    /// Relative illumination of pixel `i` (row-major).
    #[inline]
    fn vignetting_at(&self, i: usize) -> f64 {
        match self.vignetting {
            Some(v) => {
                let w = self.camera.width as usize;
                v.gain(self.camera, (i % w) as f64, (i / w) as f64)
            }
            None => 1.0,
        }
    }
}

/// [`noisy_rgb8`] through a real sensor's photometric chain ([`Photometry`]); the random
/// numbers are drawn exactly as [`noisy_rgb8`] draws them.
pub fn exposed_rgb8(colour: &[[f32; 3]], ph: &Photometry, key: NoiseKey) -> Vec<u8> {
    colour
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, c)| {
            let (n0, n1) = key.normal2(2 * i as u64);
            let n2 = key.normal(2 * i as u64 + 1);
            let n = [n0, n1, n2];
            let vig = ph.vignetting_at(i);
            (0..3).map(move |k| {
                let (level, sigma) = ph.level(c[k] as f64, vig);
                grey_level(level + sigma * n[k])
            })
        })
        .collect()
}

/// [`noisy_gray8`] through a real sensor's photometric chain ([`Photometry`]).
pub fn exposed_gray8(colour: &[[f32; 3]], ph: &Photometry, key: NoiseKey) -> Vec<u8> {
    colour
        .par_iter()
        .enumerate()
        .map(|(i, c)| {
            let l = 0.299 * c[0] as f64 + 0.587 * c[1] as f64 + 0.114 * c[2] as f64;
            let (level, sigma) = ph.level(l, ph.vignetting_at(i));
            grey_level(level + sigma * key.normal(i as u64))
        })
        .collect()
}

/// Grey from RGB8 with OpenCV's `COLOR_RGB2GRAY` fixed-point weights (as the TUM readers
/// convert the colour PNGs), so that memory and disk give the same grey image.
pub fn rgb_to_gray(rgb: &[u8]) -> Vec<u8> {
    rgb.par_chunks_exact(3)
        .map(|p| {
            ((p[0] as u32 * 4899 + p[1] as u32 * 9617 + p[2] as u32 * 1868 + 8192) >> 14) as u8
        })
        .collect()
}

/// Grey image with noise straight from linear colour (stereo: no RGB image is kept).
pub fn noisy_gray8(colour: &[[f32; 3]], sigma: f64, key: NoiseKey) -> Vec<u8> {
    colour
        .par_iter()
        .enumerate()
        .map(|(i, c)| {
            let l = 0.299 * c[0] as f64 + 0.587 * c[1] as f64 + 0.114 * c[2] as f64;
            grey_level(l + sigma * key.normal(i as u64))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{AxialNoise, DisparityQuantisation, Holes, LateralNoise};

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
    fn gray_conversion_matches_opencv_weights() {
        assert_eq!(
            rgb_to_gray(&[255, 255, 255, 0, 0, 0, 255, 0, 0]),
            vec![255, 0, 76]
        );
    }
}
