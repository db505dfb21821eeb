//! How a real colour camera turns the scene's radiance into an 8-bit image, beyond the ideal
//! pinhole snapshot: light integrated over the exposure (motion blur), rows read out one after
//! another (rolling shutter), lens vignetting, auto-exposure with gain steps, and shot plus
//! read noise, to the grey levels of the written image ([`Photometry`], [`exposed_rgb8`]; or
//! the constant grey-level noise of the older presets, [`noisy_rgb8`]). Lens distortion is the
//! camera's own `distortion` (see `render`).
//!
//! Each effect is an `Option` of [`Imaging`]; with all of them `None` a frame is rendered
//! exactly as before they existed (the older presets keep their bytes). The values the twins
//! use, with their sources, are in `catalog::twins`.
//!
//! Conventions: a frame's stamp is the instant of the middle of the exposure of the middle
//! row; row `v` (0 at the top) is exposed around `stamp + readout * ((v + 0.5) / height - 0.5)`.
//! "Radiance" is the rendered colour at the nominal exposure, in grey levels; the auto-exposure
//! scale multiplies it before noise and clipping.

use rayon::prelude::*;
use slam_core::Camera;

use crate::hash::NoiseKey;

/// The imaging effects of a colour camera; all `None` by default (an ideal snapshot).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Imaging {
    /// Light integrated over an exposure time: motion blur of camera and objects.
    pub exposure: Option<Exposure>,
    /// Rows exposed one after another over a readout time (CMOS rolling shutter).
    pub rolling_shutter: Option<RollingShutter>,
    /// Brightness falling off towards the image corners.
    pub vignetting: Option<Vignetting>,
    /// Exposure and gain following the scene's brightness with a lag, in steps.
    pub auto_exposure: Option<AutoExposure>,
    /// Photon shot noise and read noise, replacing the constant `ImageConfig::noise_sigma`.
    pub sensor_noise: Option<SensorNoise>,
}

impl Imaging {
    /// Whether colour must be rendered sample by sample in time (exposure or rolling shutter).
    pub fn is_timed(&self) -> bool {
        self.exposure.is_some() || self.rolling_shutter.is_some()
    }
}

/// Exposure integration (motion blur).
#[derive(Clone, Debug, PartialEq)]
pub struct Exposure {
    /// Nominal exposure time, seconds (auto-exposure may lengthen or shorten it).
    pub time_s: f64,
    /// Time samples averaged per pixel (>= 1); each also jitters the ray inside the pixel, so
    /// they anti-alias as well. Blur steps are `motion / samples` pixels apart.
    pub samples: u32,
}

/// Rolling shutter: row `v` is exposed `readout_s * v / height` after row 0.
#[derive(Clone, Debug, PartialEq)]
pub struct RollingShutter {
    /// Time from the first to the last row, seconds.
    pub readout_s: f64,
}

/// Vignetting: relative illumination `1 - (1 - corner) * (r / r_corner)^2` of the radius `r`
/// from the principal point, so that the image corner receives `corner` of the centre's light
/// (a parabolic fall-off, the usual first-order fit of measured vignetting).
#[derive(Clone, Debug, PartialEq)]
pub struct Vignetting {
    /// Relative illumination in the image corners, 0..=1.
    pub corner: f64,
}

impl Vignetting {
    /// Relative illumination of pixel (u, v).
    pub fn gain(&self, camera: &Camera, u: f64, v: f64) -> f64 {
        let (w, h) = (camera.width as f64, camera.height as f64);
        let corner2 =
            (camera.cx.max(w - camera.cx)).powi(2) + (camera.cy.max(h - camera.cy)).powi(2);
        let r2 = (u - camera.cx).powi(2) + (v - camera.cy).powi(2);
        1.0 - (1.0 - self.corner) * r2 / corner2
    }
}

/// Auto-exposure: each frame the camera meters the mean level of the previous frame and moves
/// its exposure scale (exposure time x gain) a share of the way, in log space, towards the
/// scale that would give `target`; the scale is quantised to gain steps. The exposure time
/// takes the scale up to `max_time_s`; gain supplies the rest (and amplifies the noise).
#[derive(Clone, Debug, PartialEq)]
pub struct AutoExposure {
    /// Mean grey level the controller aims at.
    pub target: f64,
    /// Share of the log error corrected per frame, 0..=1 (lag of the controller).
    pub rate: f64,
    /// Size of one gain step, in EV (stops; 1/8 = steps of 9 %).
    pub step_ev: f64,
    /// Longest exposure time, seconds (at most one frame period).
    pub max_time_s: f64,
    /// Largest gain.
    pub max_gain: f64,
    /// Frames of history the controller is run over to reach a frame (its state is rebuilt
    /// from scratch so that any frame can be generated alone).
    pub history: usize,
}

/// The exposure settings of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExposureSettings {
    /// Multiplier of the radiance (exposure time / nominal time x gain).
    pub scale: f64,
    /// Exposure time, seconds.
    pub time_s: f64,
    /// Analogue gain (1 = none); multiplies shot and read noise.
    pub gain: f64,
}

impl AutoExposure {
    /// One controller step: from the current `scale` and the level `metered` it produced,
    /// the next scale (quantised to `step_ev`).
    pub fn step(&self, scale: f64, metered: f64) -> f64 {
        let wanted = self.target / metered.max(1e-3);
        let log_next = scale.log2() + self.rate * wanted.log2();
        let q = (log_next / self.step_ev).round() * self.step_ev;
        2f64.powf(q)
    }

    /// The quantised scale a settled controller holds for a scene metering `radiance` at
    /// scale 1 (no clipping assumed).
    pub fn converged(&self, radiance: f64) -> f64 {
        let wanted = (self.target / radiance.max(1e-3)).log2();
        2f64.powf((wanted / self.step_ev).round() * self.step_ev)
    }

    /// Splits an exposure scale into exposure time and gain, given the nominal time.
    pub fn settings(&self, scale: f64, nominal_time_s: f64) -> ExposureSettings {
        let time = (scale * nominal_time_s).min(self.max_time_s);
        let gain = if nominal_time_s > 0.0 && time > 0.0 {
            (scale * nominal_time_s / time).min(self.max_gain)
        } else {
            scale.min(self.max_gain)
        };
        ExposureSettings {
            scale: if nominal_time_s > 0.0 {
                time / nominal_time_s * gain
            } else {
                gain
            },
            time_s: time,
            gain,
        }
    }
}

/// Shot and read noise of a CMOS sensor in grey levels: variance
/// `(gain * read_dn)^2 + gain * level / electrons_per_dn` for a pixel at `level`.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorNoise {
    /// Read noise at unit gain, grey levels.
    pub read_dn: f64,
    /// Conversion gain at unit gain: photo-electrons per grey level.
    pub electrons_per_dn: f64,
}

impl SensorNoise {
    /// Standard deviation in grey levels of a pixel at `level` (before clipping) and `gain`.
    #[inline]
    pub fn sigma(&self, level: f64, gain: f64) -> f64 {
        let read = gain * self.read_dn;
        (read * read + gain * level.max(0.0) / self.electrons_per_dn).sqrt()
    }
}

impl SensorNoise {
    /// Adds this noise at unit gain to an 8-bit grey image already captured (the perturbation
    /// layer's `image-noise`): each pixel gets N(0, sigma(its level)), rounded and clipped.
    pub fn apply_gray8(&self, grey: &[u8], key: NoiseKey) -> Vec<u8> {
        grey.par_iter()
            .enumerate()
            .map(|(i, &g)| grey_level(g as f64 + self.sigma(g as f64, 1.0) * key.normal(i as u64)))
            .collect()
    }
}

/// Sub-pixel offset (in -0.5..0.5) of time sample `k` of `n`: a rank-1 lattice (Fibonacci-like
/// over n points), so the samples of one pixel cover it evenly and each falls at its own time.
pub fn sample_offset(k: usize, n: usize) -> (f64, f64) {
    if n <= 1 {
        return (0.0, 0.0);
    }
    // Golden-ratio lattice: x = (k + 0.5) / n, y = frac(k * phi).
    let phi = 0.618_033_988_749_894_9;
    let x = (k as f64 + 0.5) / n as f64;
    let y = (k as f64 * phi + 0.5).fract();
    (x - 0.5, y - 0.5)
}

/// Time offsets of the samples of one row: sample `k` of `n` at the centre of its `1/n`-th of
/// the exposure, relative to the middle of the exposure.
pub fn sample_time(k: usize, n: usize, exposure_s: f64) -> f64 {
    exposure_s * ((k as f64 + 0.5) / n as f64 - 0.5)
}

/// Time of row `v`'s exposure centre relative to the stamp (middle row at 0).
pub fn row_time(v: f64, height: usize, readout_s: f64) -> f64 {
    readout_s * ((v + 0.5) / height as f64 - 0.5)
}

/// Rounds to the nearest grey level and clamps to 0..=255 (cheaper than `f64::round`).
#[inline]
fn grey_level(v: f64) -> u8 {
    (v + 0.5).clamp(0.0, 255.0) as u8
}

/// Adds Gaussian grey-level noise (sigma in grey levels) to linear colour and rounds to RGB8.
pub fn noisy_rgb8(colour: &[[f32; 3]], sigma: f64, key: NoiseKey) -> Vec<u8> {
    let mut out = vec![0u8; 3 * colour.len()];
    out.par_chunks_mut(3)
        .zip(colour.par_iter())
        .enumerate()
        .for_each(|(i, (o, c))| {
            let (n0, n1) = key.normal2(2 * i as u64);
            let n2 = key.normal(2 * i as u64 + 1);
            let n = [n0, n1, n2];
            for k in 0..3 {
                o[k] = grey_level(c[k] as f64 + sigma * n[k]);
            }
        });
    out
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
    pub vignetting: Option<&'a Vignetting>,
    /// Shot and read noise, if on.
    pub sensor: Option<&'a SensorNoise>,
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
    let mut out = vec![0u8; 3 * colour.len()];
    out.par_chunks_mut(3)
        .zip(colour.par_iter())
        .enumerate()
        .for_each(|(i, (o, c))| {
            let (n0, n1) = key.normal2(2 * i as u64);
            let n2 = key.normal(2 * i as u64 + 1);
            let n = [n0, n1, n2];
            let vig = ph.vignetting_at(i);
            for k in 0..3 {
                let (level, sigma) = ph.level(c[k] as f64, vig);
                o[k] = grey_level(level + sigma * n[k]);
            }
        });
    out
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
        .map(|p| slam_core::rgb_to_gray(p[0], p[1], p[2]))
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

    #[test]
    fn vignetting_is_one_at_the_centre_and_corner_in_the_corner() {
        let cam = Camera::tum_fr3();
        let v = Vignetting { corner: 0.7 };
        assert!((v.gain(&cam, cam.cx, cam.cy) - 1.0).abs() < 1e-12);
        // The farthest corner from the principal point (cx > w - cx, cy > h - cy) is (0, 0).
        let g = v.gain(&cam, 0.0, 0.0);
        assert!((g - 0.7).abs() < 1e-12, "{g}");
        for (u, w) in [(640.0, 0.0), (0.0, 480.0), (640.0, 480.0)] {
            assert!(v.gain(&cam, u, w) > 0.7);
        }
    }

    #[test]
    fn auto_exposure_converges_in_steps_and_splits_time_and_gain() {
        let ae = AutoExposure {
            target: 110.0,
            rate: 0.3,
            step_ev: 0.125,
            max_time_s: 0.03,
            max_gain: 8.0,
            history: 30,
        };
        // A scene of radiance 40 at the nominal exposure: the scale must rise towards 2.75.
        let mut s = 1.0;
        for _ in 0..30 {
            s = ae.step(s, 40.0 * s);
            let steps = s.log2() / 0.125;
            assert!((steps - steps.round()).abs() < 1e-9, "quantised to 1/8 EV");
        }
        // Within the controller's dead band: a log error whose correction is under half a step
        // is not acted on.
        let dead_band = 0.125 / (2.0 * 0.3);
        assert!((s * 40.0 / 110.0).log2().abs() <= dead_band + 1e-9, "{s}");
        assert!(s > 2.0, "{s}");
        // Nominal 10 ms, max 30 ms: a scale of 4 is 30 ms and gain 4/3.
        let st = ae.settings(4.0, 0.01);
        assert!((st.time_s - 0.03).abs() < 1e-12);
        assert!((st.gain - 4.0 / 3.0).abs() < 1e-12);
        assert!((st.scale - 4.0).abs() < 1e-12);
        let st = ae.settings(0.5, 0.01);
        assert_eq!((st.time_s, st.gain), (0.005, 1.0));
    }

    #[test]
    fn sensor_noise_variance_is_read_plus_shot() {
        let n = SensorNoise {
            read_dn: 1.5,
            electrons_per_dn: 20.0,
        };
        assert!((n.sigma(0.0, 1.0) - 1.5).abs() < 1e-12);
        assert!((n.sigma(200.0, 1.0).powi(2) - (2.25 + 10.0)).abs() < 1e-9);
        assert!((n.sigma(200.0, 2.0).powi(2) - (9.0 + 20.0)).abs() < 1e-9);
    }

    #[test]
    fn samples_cover_the_exposure_and_the_pixel_evenly() {
        let n = 8;
        let times: Vec<f64> = (0..n).map(|k| sample_time(k, n, 0.016)).collect();
        assert!((times.iter().sum::<f64>()).abs() < 1e-15);
        assert!((times[n - 1] - times[0] - 0.016 * 7.0 / 8.0).abs() < 1e-15);
        let (mut sx, mut sy) = (0.0, 0.0);
        for k in 0..n {
            let (x, y) = sample_offset(k, n);
            assert!((-0.5..0.5).contains(&x) && (-0.5..0.5).contains(&y));
            sx += x;
            sy += y;
        }
        assert!(sx.abs() < 1e-12 && (sy / n as f64).abs() < 0.1);
        assert_eq!(row_time(239.5, 480, 0.03), 0.0);
    }

    #[test]
    fn gray_conversion_matches_opencv_weights() {
        assert_eq!(
            rgb_to_gray(&[255, 255, 255, 0, 0, 0, 255, 0, 0]),
            vec![255, 0, 76]
        );
    }
}
