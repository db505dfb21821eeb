//! `occluders`: textured objects moving through the view of any sequence, real ones included.
//!
//! Each object is a fronto-parallel textured rectangle (random grey blocks of 6-12 pixels, rich
//! in corners as a poster or a box is, so ORB finds features on it) at a constant depth of
//! 0.6-1.6 m, crossing the image at 0.15-0.35 image widths per second and re-entering from the
//! other side (a cycle of a few seconds). In RGB-D it is drawn where it is nearer than the
//! measured depth (or where depth is missing), and its depth there is the rectangle's, on the
//! depth PNG grid; in stereo it is drawn in the left image at its position and in the right one
//! shifted by its disparity bf / z (stereo sequences carry no depth, so it is always in front).
//! Objects are drawn far to near, so a nearer one hides a farther one.

use slam_core::{Camera, ColourImage, DepthImage, GrayImage};
use synth::hash::{NoiseKey, Stream};
use synth::sensor::depth::quantise_png;

/// One moving object.
#[derive(Clone, Debug, PartialEq)]
pub struct Occluder {
    /// Width and height, pixels.
    pub size: (f64, f64),
    /// Depth of its surface, metres.
    pub depth: f64,
    /// Position of its top-left corner at time 0, pixels.
    pub start: (f64, f64),
    /// Velocity, pixels per second.
    pub velocity: (f64, f64),
    /// Size of its texture's blocks, pixels.
    pub block: f64,
    /// Seed of its texture.
    pub texture: u64,
}

impl Occluder {
    /// The `n` objects of perturbation seed `seed` (member seed) for a camera: a pure function
    /// of them, the same in every frame.
    pub fn objects(n: usize, seed: u64, camera: &Camera) -> Vec<Occluder> {
        let key = NoiseKey::new(seed, 0, Stream::ImageLeft);
        let (w, h) = (camera.width as f64, camera.height as f64);
        let mut v: Vec<Occluder> = (0..n)
            .map(|j| {
                let u = |k: u64| key.uniform(16 * j as u64 + k);
                let side = (0.18 + 0.17 * u(0)) * h;
                let aspect = 0.6 + 1.0 * u(1);
                let speed = (0.15 + 0.2 * u(2)) * w * if u(3) < 0.5 { -1.0 } else { 1.0 };
                Occluder {
                    size: (side * aspect.sqrt(), side / aspect.sqrt()),
                    depth: 0.6 + 1.0 * u(4),
                    start: (u(5) * w, u(6) * (h - side / aspect.sqrt()).max(1.0)),
                    velocity: (speed, (u(7) - 0.5) * 0.1 * h),
                    block: 6.0 + 6.0 * u(8),
                    texture: key.bits(16 * j as u64 + 9),
                }
            })
            .collect();
        // Far to near: a nearer object is drawn last and hides a farther one.
        v.sort_by(|a, b| b.depth.total_cmp(&a.depth));
        v
    }

    /// Top-left corner at time `t` seconds: it crosses the image and re-enters from the other
    /// side (x wraps over width + its size; y bounces within the image).
    pub fn position(&self, t: f64, width: f64, height: f64) -> (f64, f64) {
        let span = width + self.size.0;
        let x = (self.start.0 + self.velocity.0 * t).rem_euclid(span) - self.size.0;
        let range = (height - self.size.1).max(1.0);
        let y = (self.start.1 + self.velocity.1 * t).rem_euclid(2.0 * range);
        let y = if y > range { 2.0 * range - y } else { y };
        (x, y)
    }

    /// Grey level of its texture at local coordinates (x, y) pixels from its corner: random
    /// blocks with a dark 2-pixel frame.
    pub fn texture_at(&self, x: f64, y: f64) -> u8 {
        if x < 2.0 || y < 2.0 || x > self.size.0 - 2.0 || y > self.size.1 - 2.0 {
            return 20;
        }
        let (bx, by) = ((x / self.block) as u64, (y / self.block) as u64);
        let r = synth::hash::mix64(self.texture ^ synth::hash::mix64(bx << 32 | by));
        30 + (r % 200) as u8
    }
}

/// What [`draw`] draws into: the (left) grey image, and where the frame has them its depth
/// (RGB-D), right image (stereo) and colour image (drawn as the grey texture, r = g = b).
pub struct Canvas<'a> {
    /// The grey (left) image.
    pub image: &'a mut GrayImage,
    /// The depth image (RGB-D).
    pub depth: Option<&'a mut DepthImage>,
    /// The right image (stereo).
    pub right: Option<&'a mut GrayImage>,
    /// The colour image the grey one is the luma of.
    pub colour: Option<&'a mut ColourImage>,
}

/// Draws `objects` at time `t` into a frame: `image` (left), optionally `depth` (RGB-D, on the
/// PNG grid of `units` per metre) or `right` (stereo, shifted by the disparity `bf / z`).
/// Returns the number of left-image pixels drawn.
pub fn draw(
    objects: &[Occluder],
    t: f64,
    camera: &Camera,
    units: f64,
    canvas: Canvas<'_>,
) -> usize {
    let Canvas {
        image,
        mut depth,
        mut right,
        mut colour,
    } = canvas;
    let (w, h) = (image.width, image.height);
    let mut drawn = 0;
    for o in objects {
        let (x0, y0) = o.position(t, w as f64, h as f64);
        let z = quantise_png(o.depth, units);
        let disparity = camera.bf / o.depth;
        let rows =
            (y0.floor().max(0.0) as usize)..((y0 + o.size.1).ceil().max(0.0) as usize).min(h);
        for v in rows {
            for u in 0..w {
                let (lx, ly) = (u as f64 + 0.5 - x0, v as f64 + 0.5 - y0);
                if lx < 0.0 || ly < 0.0 || lx >= o.size.0 || ly >= o.size.1 {
                    continue;
                }
                let i = v * w + u;
                let g = o.texture_at(lx, ly);
                match depth.as_deref_mut() {
                    Some(d) => {
                        let measured = d.data[i];
                        if measured > 0.0 && measured <= z {
                            continue;
                        }
                        d.data[i] = z;
                    }
                    None => {
                        if let Some(r) = right.as_deref_mut() {
                            // The same surface point, seen by the right camera.
                            let ur = u as f64 - disparity;
                            if ur >= 0.0 {
                                let ur = ur.round() as usize;
                                if ur < w {
                                    r.data[v * w + ur] = g;
                                }
                            }
                        }
                    }
                }
                image.data[i] = g;
                if let Some(c) = colour.as_deref_mut() {
                    // A grey texture: its luma is g again.
                    c.data[3 * i..3 * i + 3].fill(g);
                }
                drawn += 1;
            }
        }
        // Right-image pixels whose left counterpart falls outside the left image.
        if let Some(r) = right.as_deref_mut() {
            for v in
                (y0.floor().max(0.0) as usize)..((y0 + o.size.1).ceil().max(0.0) as usize).min(h)
            {
                for ur in 0..w {
                    let ul = ur as f64 + disparity;
                    if ul.round() < w as f64 {
                        continue;
                    }
                    let (lx, ly) = (ul.round() + 0.5 - x0, v as f64 + 0.5 - y0);
                    if lx >= 0.0 && ly >= 0.0 && lx < o.size.0 && ly < o.size.1 {
                        r.data[v * w + ur] = o.texture_at(lx, ly);
                    }
                }
            }
        }
    }
    drawn
}
