//! Procedural test images for the feature tests and benchmarks: a plane covered with random
//! rotated rectangles, ellipses and striped patches (corners at every angle and scale), which
//! can be rendered through any pixel-to-scene map. Rendering the same scene rotated, scaled or
//! shifted by a sub-pixel disparity gives image pairs with exactly known correspondences.
//! (3-D sequences with depth noise are the job of the `synth` crate; this is only a texture.)

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::image::GrayImage;

/// One shape of the scene: an oriented box or ellipse with a flat or striped fill.
#[derive(Clone, Debug)]
struct Shape {
    cx: f64,
    cy: f64,
    /// Half extents along the shape's own axes.
    hw: f64,
    hh: f64,
    cos: f64,
    sin: f64,
    ellipse: bool,
    value: f64,
    /// Intensity gradient across the shape, per scene unit, along its own axes.
    gu: f64,
    gv: f64,
    /// Stripe period in scene units (0 = flat fill) and the second stripe value.
    period: f64,
    value2: f64,
}

impl Shape {
    /// Intensity at scene point (x, y) if the shape covers it.
    #[inline]
    fn sample(&self, x: f64, y: f64) -> Option<f64> {
        let dx = x - self.cx;
        let dy = y - self.cy;
        let u = dx * self.cos + dy * self.sin;
        let v = -dx * self.sin + dy * self.cos;
        let inside = if self.ellipse {
            (u / self.hw).powi(2) + (v / self.hh).powi(2) <= 1.0
        } else {
            u.abs() <= self.hw && v.abs() <= self.hh
        };
        if !inside {
            return None;
        }
        let base = if self.period > 0.0 && ((u + self.hw) / self.period).floor() as i64 % 2 == 1 {
            self.value2
        } else {
            self.value
        };
        Some(base + self.gu * u + self.gv * v)
    }
}

/// Side of the acceleration cells, scene units.
const BIN: f64 = 32.0;

/// A random planar texture (see the module doc).
#[derive(Clone, Debug)]
pub struct TestScene {
    shapes: Vec<Shape>,
    /// Shape indices per acceleration cell, topmost first.
    bins: Vec<Vec<u32>>,
    bins_x: usize,
    bins_y: usize,
    x0: f64,
    y0: f64,
    /// Plane waves (kx, ky, phase) added everywhere as fine texture.
    waves: [(f64, f64, f64); 3],
}

impl TestScene {
    /// A scene of `n_shapes` shapes spread over `[-margin, width + margin] x [-margin, height +
    /// margin]` scene units (1 unit = 1 pixel of an identity rendering), from `seed`.
    pub fn random(width: f64, height: f64, n_shapes: usize, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let margin = 0.25 * width.max(height);
        let (x0, y0) = (-margin, -margin);
        let (x1, y1) = (width + margin, height + margin);
        let mut shapes = Vec::with_capacity(n_shapes);
        for _ in 0..n_shapes {
            let size = 6.0 + 60.0 * rng.random::<f64>().powi(2);
            let aspect = 0.4 + 1.2 * rng.random::<f64>();
            let a = std::f64::consts::PI * rng.random::<f64>();
            let striped = rng.random_bool(0.2);
            shapes.push(Shape {
                cx: rng.random_range(x0..x1),
                cy: rng.random_range(y0..y1),
                hw: size,
                hh: size * aspect,
                cos: a.cos(),
                sin: a.sin(),
                ellipse: rng.random_bool(0.3),
                value: rng.random_range(10.0..245.0),
                period: if striped {
                    rng.random_range(5.0..14.0)
                } else {
                    0.0
                },
                value2: rng.random_range(10.0..245.0),
                gu: rng.random_range(-40.0..40.0) / size,
                gv: rng.random_range(-40.0..40.0) / size,
            });
        }
        let bins_x = ((x1 - x0) / BIN).ceil() as usize + 1;
        let bins_y = ((y1 - y0) / BIN).ceil() as usize + 1;
        let mut bins = vec![Vec::new(); bins_x * bins_y];
        // Painter's order: later shapes are on top, so bins list them last-first.
        for (i, s) in shapes.iter().enumerate().rev() {
            let r = s.hw.max(s.hh) * std::f64::consts::SQRT_2;
            let bx0 = (((s.cx - r - x0) / BIN).floor().max(0.0) as usize).min(bins_x - 1);
            let bx1 = (((s.cx + r - x0) / BIN).floor().max(0.0) as usize).min(bins_x - 1);
            let by0 = (((s.cy - r - y0) / BIN).floor().max(0.0) as usize).min(bins_y - 1);
            let by1 = (((s.cy + r - y0) / BIN).floor().max(0.0) as usize).min(bins_y - 1);
            for by in by0..=by1 {
                for bx in bx0..=bx1 {
                    bins[by * bins_x + bx].push(i as u32);
                }
            }
        }
        let waves = std::array::from_fn(|_| {
            let f = rng.random_range(0.05..0.4);
            let a = std::f64::consts::TAU * rng.random::<f64>();
            (
                f * a.cos(),
                f * a.sin(),
                std::f64::consts::TAU * rng.random::<f64>(),
            )
        });
        TestScene {
            shapes,
            waves,
            bins,
            bins_x,
            bins_y,
            x0,
            y0,
        }
    }

    /// Intensity (0..255) at scene point (x, y): the topmost shape there (flat or striped, with
    /// a linear gradient), or a smooth background, plus a fine texture of three plane waves.
    pub fn intensity(&self, x: f64, y: f64) -> f64 {
        let texture: f64 = self
            .waves
            .iter()
            .map(|&(kx, ky, ph)| 8.0 * (kx * x + ky * y + ph).sin())
            .sum();
        (self.base(x, y) + texture).clamp(0.0, 255.0)
    }

    /// The shapes, or the background, without the wave texture.
    fn base(&self, x: f64, y: f64) -> f64 {
        let bx = ((x - self.x0) / BIN).floor();
        let by = ((y - self.y0) / BIN).floor();
        if bx >= 0.0 && by >= 0.0 && (bx as usize) < self.bins_x && (by as usize) < self.bins_y {
            for &i in &self.bins[by as usize * self.bins_x + bx as usize] {
                if let Some(v) = self.shapes[i as usize].sample(x, y) {
                    return v;
                }
            }
        }
        128.0 + 40.0 * (0.013 * x).sin() * (0.017 * y).cos()
    }

    /// Renders a `width x height` image whose pixel (u, v) shows the scene at `map(u, v)`,
    /// averaging 4x4 sub-samples per pixel (anti-aliasing), so edges have sub-pixel accuracy.
    pub fn render(
        &self,
        width: usize,
        height: usize,
        map: impl Fn(f64, f64) -> (f64, f64),
    ) -> GrayImage {
        let mut img = GrayImage::new(width, height);
        const N: usize = 4;
        for v in 0..height {
            for u in 0..width {
                let mut acc = 0.0;
                for j in 0..N {
                    for i in 0..N {
                        let su = u as f64 + (i as f64 + 0.5) / N as f64 - 0.5;
                        let sv = v as f64 + (j as f64 + 0.5) / N as f64 - 0.5;
                        let (x, y) = map(su, sv);
                        acc += self.intensity(x, y);
                    }
                }
                img.data[v * width + u] = (acc / (N * N) as f64).round().clamp(0.0, 255.0) as u8;
            }
        }
        img
    }
}

/// A 640x480 identity rendering of `TestScene::random(640, 480, 400, seed)`: the standard
/// test frame of the feature tests and benchmarks.
pub fn test_frame(seed: u64) -> GrayImage {
    TestScene::random(640.0, 480.0, 400, seed).render(640, 480, |u, v| (u, v))
}
