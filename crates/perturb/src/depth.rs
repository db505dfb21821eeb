//! The depth families on one measured depth image, through synth's depth-sensor model
//! (`synth::sensor::depth`): the same sigma(z), lateral offset, blob-hole and flying-pixel
//! models the synthetic sequences are rendered with. Every output stays on the grid of the
//! sequence's depth PNG (`units` per metre), so a written folder reads back to the same bits.

use slam_core::{Camera, DepthImage};
use synth::hash::{NoiseKey, Stream};
use synth::sensor::depth::{sensor_depth, DepthNoise};
use synth::{AxialNoise, BlobHoles, FlyingPixels, LateralNoise, SystematicDistortion};

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
        Family::DepthScale => model(DepthNoise {
            distortion: Some(SystematicDistortion {
                scale_error: level / 100.0,
                wobble_amplitude: 0.0,
                wobble_period_px: 180.0,
            }),
            ..DepthNoise::default()
        }),
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
