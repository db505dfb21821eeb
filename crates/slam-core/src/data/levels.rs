//! The image-pyramid scale table in `f64`, shared by every frame and keyframe of a run (all come
//! from the same ORB extractor). Used for search radii, measurement noise (sigma^2 per octave) and
//! the scale-invariance distance range of map points.

/// Per-octave scale factors and measurement variances (ORB-SLAM2: sigma^2 = scale^2).
#[derive(Clone, Debug, PartialEq)]
pub struct ScaleLevels {
    /// Number of pyramid levels (ORB-SLAM2: 8).
    pub n_levels: usize,
    /// Scale factor between consecutive levels (ORB-SLAM2: 1.2).
    pub scale_factor: f64,
    /// `ln(scale_factor)`, for predicting the level of a map point from its distance.
    pub log_scale_factor: f64,
    /// `scale_factor^level`.
    pub scale_factors: Vec<f64>,
    /// Measurement variance of a keypoint of this octave, pixels^2.
    pub level_sigma2: Vec<f64>,
    /// Inverse of `level_sigma2`: the information weight of an observation.
    pub inv_level_sigma2: Vec<f64>,
}

impl ScaleLevels {
    /// The table of a pyramid with `n_levels` levels and ratio `scale_factor`.
    pub fn new(n_levels: usize, scale_factor: f64) -> Self {
        let n_levels = n_levels.max(1);
        let scale_factors: Vec<f64> = (0..n_levels).map(|l| scale_factor.powi(l as i32)).collect();
        let level_sigma2: Vec<f64> = scale_factors.iter().map(|s| s * s).collect();
        let inv_level_sigma2 = level_sigma2.iter().map(|s| 1.0 / s).collect();
        ScaleLevels {
            n_levels,
            scale_factor,
            log_scale_factor: scale_factor.ln(),
            scale_factors,
            level_sigma2,
            inv_level_sigma2,
        }
    }

    /// Scale factor of an octave (clamped to the pyramid).
    #[inline]
    pub fn scale(&self, octave: usize) -> f64 {
        self.scale_factors[octave.min(self.n_levels - 1)]
    }

    /// Variance of an octave, pixels^2 (clamped to the pyramid).
    #[inline]
    pub fn sigma2(&self, octave: usize) -> f64 {
        self.level_sigma2[octave.min(self.n_levels - 1)]
    }

    /// Inverse variance of an octave (clamped to the pyramid).
    #[inline]
    pub fn inv_sigma2(&self, octave: usize) -> f64 {
        self.inv_level_sigma2[octave.min(self.n_levels - 1)]
    }

    /// Scale factor of the coarsest level.
    pub fn max_scale(&self) -> f64 {
        self.scale_factors[self.n_levels - 1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orbslam2_sigma_table() {
        let l = ScaleLevels::new(8, 1.2);
        let expected = [
            1.0, 1.44, 2.0736, 2.98598, 4.29982, 6.19174, 8.9161, 12.8392,
        ];
        for (a, b) in l.level_sigma2.iter().zip(expected) {
            assert!((a - b).abs() < 1e-4, "{a} vs {b}");
        }
        assert!((l.inv_sigma2(1) * l.sigma2(1) - 1.0).abs() < 1e-12);
        assert_eq!(l.scale(20), l.max_scale());
    }
}
