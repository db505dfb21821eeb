//! The depth families on one measured depth image, through synth's depth-sensor model
//! (`synth::sensor::depth`): the same sigma(z), lateral offset, blob-hole and flying-pixel
//! models the synthetic sequences are rendered with. Every output stays on the grid of the
//! sequence's depth PNG (`units` per metre), so a written folder reads back to the same bits.

use slam_core::{Camera, DepthImage};
use synth::hash::{NoiseKey, Stream};
use synth::sensor::depth::quantise_png;
use synth::sensor::depth::{sensor_depth, DepthNoise};
use synth::{AxialNoise, BlobHoles, FlyingPixels, LateralNoise};

use crate::family::Family;
use crate::systematic;

/// Applies depth family `family` at `level` to `depth` (frame `frame`, member seed `seed`).
/// Families that are not per-image depth changes (lag, offset) return it unchanged.
pub fn apply(
    family: Family,
    level: f64,
    depth: &DepthImage,
    camera: &Camera,
    units: f64,
    seed: u64,
    frame: usize,
) -> DepthImage {
    let (w, h) = (depth.width, depth.height);
    // sensor_depth reads the image size from the camera.
    let cam = Camera {
        width: w as u32,
        height: h as u32,
        ..camera.clone()
    };
    let model = |m: DepthNoise| -> DepthImage {
        let cos = vec![1.0f32; w * h];
        DepthImage {
            width: w,
            height: h,
            data: sensor_depth(&m, units, &cam, &depth.data, &cos, seed, frame),
        }
    };
    match family {
        Family::DepthAxial => model(DepthNoise {
            axial: Some(scaled_axial(level)),
            ..DepthNoise::default()
        }),
        Family::DepthLateral => model(DepthNoise {
            lateral: Some(LateralNoise { sigma_px: level }),
            ..DepthNoise::default()
        }),
        Family::DepthScale => depth_scale(depth, level, units),
        Family::DepthHoles => {
            let mut out = depth.clone();
            let s = w as f64 / 640.0;
            BlobHoles {
                share: level / 100.0,
                radius_px: (3.0 * s, 14.0 * s),
            }
            .apply(
                &mut out.data,
                w,
                h,
                NoiseKey::new(seed, frame, Stream::BoundaryHole),
            );
            out
        }
        Family::DepthEdges => DepthImage {
            width: w,
            height: h,
            data: FlyingPixels {
                band_px: level as usize,
                jump: synth::Holes::default().boundary_jump,
            }
            .apply(
                &depth.data,
                w,
                h,
                units,
                NoiseKey::new(seed, frame, Stream::Lateral),
            ),
        },
        Family::DepthDistortion => systematic::depth_distortion(depth, level, units, seed),
        Family::DepthRegistration => systematic::depth_registration(depth, level, seed),
        Family::IrShadow => systematic::ir_shadow(depth, level, camera),
        Family::DisparityQuantization => {
            systematic::disparity_quantization(depth, level, units, seed, frame)
        }
        _ => depth.clone(),
    }
}

/// `depth-scale` at `level` %: every valid depth times 1 + level / 100, on the PNG grid. The
/// arithmetic of synth's sensor model with a scale error and no wobble (`SystematicDistortion`
/// with `wobble_amplitude` 0), without the per-pixel radius and cosine that model spends on a
/// wobble of zero: the same bits on any depth image as read (no negative depths), a twelfth
/// of the time.
pub fn depth_scale(depth: &DepthImage, level: f64, units: f64) -> DepthImage {
    let factor = 1.0 + level / 100.0;
    systematic::map_valid(depth, |_, z| {
        if z.is_finite() {
            quantise_png(z * factor, units)
        } else {
            0.0
        }
    })
}

/// Nguyen's axial model at normal incidence, its sigma times `k`.
pub fn scaled_axial(k: f64) -> AxialNoise {
    let d = AxialNoise::default();
    AxialNoise {
        a: d.a * k,
        b: d.b * k,
        z0: d.z0,
        grazing: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use synth::sensor::depth::sensor_depth;
    use synth::SystematicDistortion;

    #[test]
    fn depth_scale_is_the_sensor_model_s_scale_error_bit_for_bit() {
        let camera = Camera::tum_fr3();
        let (w, h) = (camera.width as usize, camera.height as usize);
        // Depths across the PNG's range, holes, and values that fall off it when scaled.
        let depth: Vec<f32> = (0..w * h)
            .map(|i| match i % 97 {
                0 => 0.0,
                1 => f32::NAN,
                2 => 13.1,
                k => 0.3 + 0.0371 * k as f32 + 1e-4 * (i / w) as f32,
            })
            .collect();
        let image = DepthImage {
            width: w,
            height: h,
            data: depth.clone(),
        };
        let cos = vec![1.0f32; w * h];
        for level in [-50.0, -3.381642512, 0.0, 0.7, 5.0, 50.0] {
            for units in [5000.0, 1000.0] {
                let model = DepthNoise {
                    distortion: Some(SystematicDistortion {
                        scale_error: level / 100.0,
                        wobble_amplitude: 0.0,
                        wobble_period_px: 180.0,
                    }),
                    ..DepthNoise::default()
                };
                let by_model = sensor_depth(&model, units, &camera, &depth, &cos, 7, 3);
                let ours = depth_scale(&image, level, units);
                let bits = |d: &[f32]| d.iter().map(|z| z.to_bits()).collect::<Vec<_>>();
                assert!(
                    bits(&ours.data) == bits(&by_model),
                    "level {level}, units {units}"
                );
            }
        }
    }
}
