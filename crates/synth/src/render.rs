//! The ray-caster: renders a view of the placed scene through a pinhole camera into a
//! z-depth image, incidence angles, object ids and (optionally) a Lambertian-shaded,
//! anti-aliased colour image. Rows are rendered in parallel with rayon; the output is a pure
//! function of the inputs, so it is bit-identical for any number of threads.

use nalgebra::{Isometry3, Vector3};
use rayon::prelude::*;
use slam_core::Camera;

use crate::config::Supersampling;
use crate::scene::{Placed, Scene, OCCLUDER_ID};

/// Depth of the featureless occluder of the occlusion window, metres.
pub const OCCLUDER_DEPTH: f32 = 0.5;
/// Grey level of the occluder.
const OCCLUDER_GREY: f32 = 118.0;

/// What the ray-caster produces for one view, row-major, `width * height` entries each.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// Exact z-depth (along the optical axis) of the pixel-centre ray, metres.
    pub depth: Vec<f32>,
    /// Cosine of the incidence angle between the pixel-centre ray and the surface normal.
    pub cos_incidence: Vec<f32>,
    /// Id of the object hit by the pixel-centre ray.
    pub ids: Vec<u16>,
    /// Linear RGB in grey levels (0..255 floats, before noise), when colour was asked for.
    pub colour: Option<Vec<[f32; 3]>>,
}

/// Colour settings of a render.
#[derive(Clone, Copy, Debug)]
pub struct Shading {
    /// Anti-aliasing pattern.
    pub supersampling: Supersampling,
    /// Ambient share of the light, 0..1.
    pub ambient: f64,
}

/// One view to render.
pub struct View<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Its objects placed at the view's time.
    pub placed: &'a [Placed],
    /// Intrinsics and image size.
    pub camera: &'a Camera,
    /// Camera-to-world pose.
    pub pose_wc: Isometry3<f64>,
    /// Whether the featureless occluder covers the lens.
    pub occluded: bool,
}

struct Sample {
    t: f32,
    cos: f32,
    id: u16,
    colour: [f32; 3],
}

impl View<'_> {
    /// Casts the ray through (undistorted) pixel coordinates (u, v) and shades it when `shade`.
    #[inline]
    fn cast(&self, placed: &[Placed], u: f64, v: f64, shade: Option<&Shading>) -> Sample {
        let c = self.camera;
        let dc = Vector3::new((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
        if self.occluded {
            return Sample {
                t: OCCLUDER_DEPTH,
                cos: (1.0 / dc.norm()) as f32,
                id: OCCLUDER_ID,
                colour: [OCCLUDER_GREY; 3],
            };
        }
        let o = self.pose_wc.translation.vector;
        let d = self.pose_wc.rotation * dc;
        let hit = self.scene.intersect(placed, &o, &d);
        let cos = (-hit.normal.dot(&d) / d.norm()).clamp(0.0, 1.0);
        let colour = match shade {
            Some(s) => {
                let p = o + d * hit.t;
                let l = (self.scene.light - p).normalize();
                let lambert = hit.normal.dot(&l).max(0.0);
                let k = (s.ambient + (1.0 - s.ambient) * lambert) as f32;
                let a = self.scene.textures[hit.texture].sample(hit.st.0, hit.st.1);
                [a[0] * k, a[1] * k, a[2] * k]
            }
            None => [0.0; 3],
        };
        Sample {
            t: hit.t as f32,
            cos: cos as f32,
            id: hit.id,
            colour,
        }
    }

    /// Conservative image-space bounds (u0, u1, v0, v1) of each placed object's bounding
    /// sphere, or the whole plane when the sphere reaches behind the camera.
    fn screen_bounds(&self) -> Vec<[f64; 4]> {
        let c = self.camera;
        let inv = self.pose_wc.inverse();
        let all = [
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
        ];
        self.placed
            .iter()
            .map(|p| {
                let q = inv * nalgebra::Point3::from(p.centre);
                let r = p.radius;
                if q.z - r < 0.02 {
                    return all;
                }
                // x / z over the box [q - r, q + r] is extreme at its corners.
                let lo = |a: f64| {
                    if a - r <= 0.0 {
                        (a - r) / (q.z - r)
                    } else {
                        (a - r) / (q.z + r)
                    }
                };
                let hi = |a: f64| {
                    if a + r >= 0.0 {
                        (a + r) / (q.z - r)
                    } else {
                        (a + r) / (q.z + r)
                    }
                };
                [
                    c.fx * lo(q.x) + c.cx - 1.0,
                    c.fx * hi(q.x) + c.cx + 1.0,
                    c.fy * lo(q.y) + c.cy - 1.0,
                    c.fy * hi(q.y) + c.cy + 1.0,
                ]
            })
            .collect()
    }

    /// Casts `n` rays at (x0 + k, y), k = 0..n, testing per 16-ray segment only the objects
    /// whose image bounds overlap it.
    fn row(
        &self,
        bounds: &[[f64; 4]],
        x0: f64,
        y: f64,
        n: usize,
        shade: Option<&Shading>,
    ) -> Vec<Sample> {
        let row_objs: Vec<usize> = (0..self.placed.len())
            .filter(|&i| bounds[i][2] <= y && y <= bounds[i][3])
            .collect();
        let mut seg: Vec<Placed> = Vec::with_capacity(row_objs.len());
        let mut out = Vec::with_capacity(n);
        const SEG: usize = 16;
        for s in (0..n).step_by(SEG) {
            let (xa, xb) = (x0 + s as f64, x0 + (s + SEG - 1).min(n - 1) as f64);
            seg.clear();
            seg.extend(
                row_objs
                    .iter()
                    .filter(|&&i| bounds[i][0] <= xb && xa <= bounds[i][1])
                    .map(|&i| self.placed[i]),
            );
            for k in s..(s + SEG).min(n) {
                out.push(self.cast(&seg, x0 + k as f64, y, shade));
            }
        }
        out
    }

    /// Renders the view; colour only when `shading` is given.
    pub fn render(&self, shading: Option<Shading>) -> RenderOutput {
        let (w, h) = (self.camera.width as usize, self.camera.height as usize);
        let sh = shading.as_ref();
        let bounds = self.screen_bounds();
        let b = &bounds;
        // Pixel-centre rays: depth, incidence, id, and the centre colour sample.
        let centre: Vec<Sample> = (0..h)
            .into_par_iter()
            .flat_map_iter(|v| self.row(b, 0.0, v as f64, w, sh))
            .collect();
        let colour = shading.map(|s| match s.supersampling {
            Supersampling::None => centre.iter().map(|c| c.colour).collect(),
            Supersampling::Quincunx => {
                let corners: Vec<[f32; 3]> = (0..=h)
                    .into_par_iter()
                    .flat_map_iter(|v| {
                        self.row(b, -0.5, v as f64 - 0.5, w + 1, sh)
                            .into_iter()
                            .map(|s| s.colour)
                    })
                    .collect();
                (0..h)
                    .into_par_iter()
                    .flat_map_iter(|v| (0..w).map(move |u| (u, v)))
                    .map(|(u, v)| {
                        let c = centre[v * w + u].colour;
                        let k = |x: usize, y: usize| corners[y * (w + 1) + x];
                        let (a, b, cc, d) = (k(u, v), k(u + 1, v), k(u, v + 1), k(u + 1, v + 1));
                        let mut out = [0.0; 3];
                        for i in 0..3 {
                            out[i] = 0.5 * c[i] + 0.125 * (a[i] + b[i] + cc[i] + d[i]);
                        }
                        out
                    })
                    .collect()
            }
            Supersampling::Grid(n) => {
                let n = n.max(1) as usize;
                let inv = 1.0 / (n * n) as f32;
                let off = |i: usize| (i as f64 + 0.5) / n as f64 - 0.5;
                (0..h)
                    .into_par_iter()
                    .flat_map_iter(|v| {
                        let mut acc = vec![[0.0f32; 3]; w];
                        for j in 0..n {
                            for i in 0..n {
                                let r = self.row(b, off(i), v as f64 + off(j), w, sh);
                                for (a, s) in acc.iter_mut().zip(&r) {
                                    for (ak, ck) in a.iter_mut().zip(s.colour) {
                                        *ak += ck;
                                    }
                                }
                            }
                        }
                        acc.into_iter().map(move |a| a.map(|x| x * inv))
                    })
                    .collect()
            }
        });
        RenderOutput {
            width: w,
            height: h,
            depth: centre.iter().map(|s| s.t).collect(),
            cos_incidence: centre.iter().map(|s| s.cos).collect(),
            ids: centre.iter().map(|s| s.id).collect(),
            colour,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trajectory::pose_at;

    /// All anti-aliasing patterns see the same geometry and nearly the same colours; more rays
    /// only smooth edges.
    #[test]
    fn supersampling_patterns_agree() {
        let scene = Scene::new(1, None);
        let placed = scene.place(0.0);
        let mut cam = Camera::tum_fr3();
        (cam.width, cam.height, cam.cx, cam.cy) = (160, 120, 80.0, 60.0);
        let view = View {
            scene: &scene,
            placed: &placed,
            camera: &cam,
            pose_wc: pose_at(&crate::config::Trajectory::Xyz, 0.0),
            occluded: false,
        };
        let render = |s| {
            view.render(Some(Shading {
                supersampling: s,
                ambient: 0.45,
            }))
        };
        let none = render(Supersampling::None);
        let quin = render(Supersampling::Quincunx);
        let grid = render(Supersampling::Grid(3));
        assert_eq!(none.depth, grid.depth);
        assert_eq!(none.ids, quin.ids);
        let mad = |a: &RenderOutput, b: &RenderOutput| {
            let (a, b) = (a.colour.as_ref().unwrap(), b.colour.as_ref().unwrap());
            a.iter()
                .zip(b)
                .map(|(x, y)| (x[1] - y[1]).abs() as f64)
                .sum::<f64>()
                / a.len() as f64
        };
        assert!(
            mad(&quin, &grid) < mad(&none, &grid),
            "quincunx is closer to the 3x3 grid"
        );
        assert!(mad(&quin, &grid) < 15.0);
        // Depth-only renders give the same depth.
        assert_eq!(view.render(None).depth, none.depth);
    }
}
