//! The ray-caster: renders a view of the placed scene through the camera (pinhole, or with the
//! camera's radial-tangential lens distortion written into the image) into a z-depth image,
//! incidence angles, object ids and (optionally) a Lambertian-shaded, anti-aliased colour
//! image; [`Exposed::render`] renders colour sample by sample in time (motion blur, rolling
//! shutter). Rows are rendered in parallel with rayon; the output is a pure function of the
//! inputs, so it is bit-identical for any number of threads.

use nalgebra::{Isometry3, Vector3};
use rayon::prelude::*;
use slam_core::{Camera, Distortion};

use crate::world::scene::{Placed, Scene, Seen, OCCLUDER_ID};

/// How many rays are averaged for a pixel's colour (depth always comes from the pixel centre).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Supersampling {
    /// One ray through the pixel centre (aliased edges).
    None,
    /// Centre ray weighted 1/2 plus the four pixel corners weighted 1/8 each (corners shared
    /// with the neighbours): about 2 rays per pixel. Default.
    Quincunx,
    /// An n x n grid of rays inside the pixel (n >= 2), plus the centre ray for depth.
    Grid(u32),
}

/// Photometric settings of the rendered images.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageConfig {
    /// Standard deviation of the additive Gaussian grey-level noise, in grey levels (default 2.0).
    pub noise_sigma: f64,
    /// Anti-aliasing (default [`Supersampling::Quincunx`]).
    pub supersampling: Supersampling,
    /// Ambient share of the Lambertian shading, 0..1 (default 0.45).
    pub ambient: f64,
}

impl Default for ImageConfig {
    fn default() -> Self {
        ImageConfig {
            noise_sigma: 2.0,
            supersampling: Supersampling::Quincunx,
            ambient: 0.45,
        }
    }
}

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

#[derive(Clone, Copy, Default)]
struct Sample {
    t: f32,
    cos: f32,
    id: u16,
    colour: [f32; 3],
}

impl View<'_> {
    /// The camera-frame direction (z = 1) of the ray through raw pixel coordinates (u, v),
    /// through the lens distortion when the camera has one.
    #[inline]
    fn ray_camera(&self, rays: Option<&RayTable>, u: f64, v: f64) -> Vector3<f64> {
        let c = self.camera;
        match rays {
            None => Vector3::new((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0),
            Some(r) => {
                let (x, y) = r.ray(c, u, v);
                Vector3::new(x, y, 1.0)
            }
        }
    }

    /// Casts the ray of camera-frame direction `dc` (world direction `d`, `None` when the
    /// occluder covers the lens) and shades it when `shade`. Inlined into each caller, so a
    /// caller that keeps only the colour (or only the geometry) does not pay for the rest.
    #[inline(always)]
    fn cast(
        &self,
        seen: &[Seen],
        dc: &Vector3<f64>,
        d: Option<&Vector3<f64>>,
        shade: Option<&Shading>,
    ) -> Sample {
        let Some(d) = d else {
            return Sample {
                t: OCCLUDER_DEPTH,
                cos: (1.0 / dc.norm()) as f32,
                id: OCCLUDER_ID,
                colour: [OCCLUDER_GREY; 3],
            };
        };
        let o = self.pose_wc.translation.vector;
        let hit = self.scene.intersect_seen(seen, &o, d);
        let cos = (-hit.normal.dot(d) / d.norm()).clamp(0.0, 1.0);
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
    /// sphere, or the whole plane when the sphere reaches behind the camera; through the lens
    /// distortion when the camera has one.
    fn screen_bounds(&self) -> Vec<[f64; 4]> {
        let pinhole = self.pinhole_bounds();
        if self.camera.distortion.is_none() {
            return pinhole;
        }
        pinhole
            .into_iter()
            .map(|b| distort_bounds(self.camera, b))
            .collect()
    }

    /// [`View::screen_bounds`] of an ideal pinhole camera.
    fn pinhole_bounds(&self) -> Vec<[f64; 4]> {
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

    /// The placed objects as the view's rays meet them ([`Scene::seen_from`]).
    fn seen(&self) -> Vec<Seen> {
        let mut out = Vec::new();
        self.seen_into(&mut out);
        out
    }

    /// [`View::seen`] into `out` (cleared first).
    fn seen_into(&self, out: &mut Vec<Seen>) {
        let o = self.pose_wc.translation.vector;
        out.clear();
        out.extend(self.placed.iter().map(|p| self.scene.seen_from(p, &o)));
    }

    /// The ray table of the view's camera when it has a lens distortion ([`ray_table`]).
    fn rays(&self) -> Option<std::sync::Arc<RayTable>> {
        self.camera.distortion.map(|_| ray_table(self.camera))
    }

    /// Casts `n` rays at (x0 + k, y), k = 0..n (through `rays`, [`View::rays`]), and hands
    /// each sample to `emit(k, sample)` in order, testing per 16-ray segment only the objects whose image bounds overlap it and
    /// whose bounding sphere the segment's cone of rays reaches ([`RayCone`]): the objects
    /// left out are those every ray of the segment misses by a wide margin, so each ray finds
    /// the hit it would find testing every object. `seen` is [`View::seen`].
    #[allow(clippy::too_many_arguments)]
    fn row(
        &self,
        rays: Option<&RayTable>,
        seen: &[Seen],
        bounds: &[[f64; 4]],
        x0: f64,
        y: f64,
        n: usize,
        shade: Option<&Shading>,
        mut emit: impl FnMut(usize, Sample),
    ) {
        const SEG: usize = 16;
        let row_objs: Vec<usize> = (0..bounds.len())
            .filter(|&i| bounds[i][2] <= y && y <= bounds[i][3])
            .collect();
        let mut seg: Vec<Seen> = Vec::with_capacity(row_objs.len());
        let mut dirs = [(Vector3::zeros(), Vector3::zeros()); SEG];
        for s in (0..n).step_by(SEG) {
            let m = SEG.min(n - s);
            let (xa, xb) = (x0 + s as f64, x0 + (s + m - 1) as f64);
            for (j, dir) in dirs.iter_mut().enumerate().take(m) {
                let dc = self.ray_camera(rays, x0 + (s + j) as f64, y);
                *dir = (dc, self.pose_wc.rotation * dc);
            }
            let dirs = &dirs[..m];
            if self.occluded {
                for (j, (dc, _)) in dirs.iter().enumerate() {
                    emit(s + j, self.cast(&[], dc, None, shade));
                }
                continue;
            }
            seg.clear();
            let mut cone = None;
            for &i in &row_objs {
                let b = &bounds[i];
                if !(b[0] <= xb && xa <= b[1]) {
                    continue;
                }
                let cone = cone.get_or_insert_with(|| {
                    RayCone::of_camera(dirs.iter().map(|(dc, _)| dc), &self.pose_wc.rotation)
                });
                if cone.may_reach(&seen[i]) {
                    seg.push(seen[i]);
                }
            }
            for (j, (dc, d)) in dirs.iter().enumerate() {
                emit(s + j, self.cast(&seg, dc, Some(d), shade));
            }
        }
    }

    /// Renders the view; colour only when `shading` is given.
    pub fn render(&self, shading: Option<Shading>) -> RenderOutput {
        let (w, h) = (self.camera.width as usize, self.camera.height as usize);
        let sh = shading.as_ref();
        let bounds = self.screen_bounds();
        let b = &bounds;
        let seen = self.seen();
        let seen = &seen;
        let rays = self.rays();
        let rays = rays.as_deref();
        // Pixel-centre rays: depth, incidence, id, and the centre colour sample.
        let mut depth = vec![0.0f32; w * h];
        let mut cos_incidence = vec![0.0f32; w * h];
        let mut ids = vec![0u16; w * h];
        let mut centre_colour = vec![[0.0f32; 3]; if sh.is_some() { w * h } else { 0 }];
        let colour_rows: Vec<&mut [[f32; 3]]> = if sh.is_some() {
            centre_colour.chunks_mut(w).collect()
        } else {
            (0..h).map(|_| Default::default()).collect()
        };
        depth
            .par_chunks_mut(w)
            .zip(cos_incidence.par_chunks_mut(w))
            .zip(ids.par_chunks_mut(w))
            .zip(colour_rows)
            .enumerate()
            .for_each(|(v, (((dr, cr), ir), colr))| {
                self.row(rays, seen, b, 0.0, v as f64, w, sh, |k, s| {
                    dr[k] = s.t;
                    cr[k] = s.cos;
                    ir[k] = s.id;
                    if let Some(c) = colr.get_mut(k) {
                        *c = s.colour;
                    }
                });
            });
        let colour = shading.map(|s| match s.supersampling {
            Supersampling::None => centre_colour,
            Supersampling::Quincunx => {
                let mut corners = vec![[0.0f32; 3]; (w + 1) * (h + 1)];
                corners
                    .par_chunks_mut(w + 1)
                    .enumerate()
                    .for_each(|(v, row)| {
                        self.row(rays, seen, b, -0.5, v as f64 - 0.5, w + 1, sh, |k, s| {
                            row[k] = s.colour
                        });
                    });
                let mut out = vec![[0.0f32; 3]; w * h];
                out.par_chunks_mut(w).enumerate().for_each(|(v, row)| {
                    let k = |x: usize, y: usize| corners[y * (w + 1) + x];
                    for (u, o) in row.iter_mut().enumerate() {
                        let c = centre_colour[v * w + u];
                        let (a, b, cc, d) = (k(u, v), k(u + 1, v), k(u, v + 1), k(u + 1, v + 1));
                        for i in 0..3 {
                            o[i] = 0.5 * c[i] + 0.125 * (a[i] + b[i] + cc[i] + d[i]);
                        }
                    }
                });
                out
            }
            Supersampling::Grid(n) => {
                let n = n.max(1) as usize;
                let inv = 1.0 / (n * n) as f32;
                let off = |i: usize| (i as f64 + 0.5) / n as f64 - 0.5;
                let mut out = vec![[0.0f32; 3]; w * h];
                out.par_chunks_mut(w).enumerate().for_each(|(v, acc)| {
                    for j in 0..n {
                        for i in 0..n {
                            self.row(rays, seen, b, off(i), v as f64 + off(j), w, sh, |k, s| {
                                for (ak, ck) in acc[k].iter_mut().zip(s.colour) {
                                    *ak += ck;
                                }
                            });
                        }
                    }
                    for a in acc.iter_mut() {
                        *a = a.map(|x| x * inv);
                    }
                });
                out
            }
        });
        RenderOutput {
            width: w,
            height: h,
            depth,
            cos_incidence,
            ids,
            colour,
        }
    }
}

/// A cone from the camera centre holding a set of rays: its unit axis and the cosine and
/// sine of its half-angle, widened by a margin far beyond the rounding of any of the
/// arithmetic involved.
struct RayCone {
    axis: Vector3<f64>,
    cos: f64,
    sin: f64,
}

/// Margin (on cosines) of [`RayCone`]'s tests: 1e-7, against roundings of about 1e-15.
const CONE_MARGIN: f64 = 1e-7;

impl RayCone {
    /// A cone holding the world directions `rotation * dc` of camera-frame directions `dc`
    /// (z = 1; not empty): the cone around the centre of their (x, y) bounding box holding its
    /// four corners, turned into the world. The box is convex and a cone of half-angle under
    /// 90 degrees is convex, so holding the corners it holds every ray inside the box; the
    /// rotation keeps angles to about 1e-16, far inside [`CONE_MARGIN`]. Five square roots per
    /// segment (the cone of the rays themselves took two per ray).
    fn of_camera<'a>(
        dcs: impl Iterator<Item = &'a Vector3<f64>>,
        rotation: &nalgebra::UnitQuaternion<f64>,
    ) -> RayCone {
        let mut b = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for d in dcs {
            b[0] = b[0].min(d.x);
            b[1] = b[1].max(d.x);
            b[2] = b[2].min(d.y);
            b[3] = b[3].max(d.y);
        }
        let centre = Vector3::new(0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 1.0);
        let axis = centre / centre.norm();
        let cos = [(b[0], b[2]), (b[0], b[3]), (b[1], b[2]), (b[1], b[3])]
            .iter()
            .map(|&(x, y)| {
                let c = Vector3::new(x, y, 1.0);
                axis.dot(&c) / c.norm()
            })
            .fold(1.0f64, f64::min)
            - CONE_MARGIN;
        let cos = cos.max(-1.0);
        RayCone {
            axis: rotation * axis,
            cos,
            sin: (1.0 - cos * cos).max(0.0).sqrt(),
        }
    }

    /// Whether a ray of the cone may come near the bounding sphere of `seen` (centre `v`
    /// relative to the camera centre, radius r): `false` only when the angle between the axis and `v`
    /// exceeds the cone's half-angle plus the sphere's angular radius by the margin, so that
    /// every ray of the cone (a half-line) misses the sphere by far more than rounding.
    #[inline]
    fn may_reach(&self, seen: &Seen) -> bool {
        let (v, l2) = (seen.oc(), seen.oc2());
        let r_safe = seen.placed().radius * (1.0 + 1e-6) + 1e-9;
        if l2 <= r_safe * r_safe {
            return true;
        }
        let l = l2.sqrt();
        let sin_phi = r_safe / l;
        let cos_phi = (1.0 - sin_phi * sin_phi).max(0.0).sqrt();
        // cos(theta + phi): the smallest cosine to the axis of a direction within the sphere's
        // angular radius of a ray of the cone.
        let cos_limit = self.cos * cos_phi - self.sin * sin_phi;
        self.axis.dot(v) / l >= cos_limit - CONE_MARGIN
    }
}

/// The rays of a distorted camera: the ideal normalised coordinates of every pixel centre and
/// the local Jacobian of the undistortion, so a ray anywhere in the image costs a lookup and a
/// first-order step (under 1e-4 pixel from the exact inverse within half a pixel of a centre).
pub struct RayTable {
    width: usize,
    height: usize,
    xy: Vec<[f64; 2]>,
    jacobian: Vec<[f32; 4]>,
}

impl RayTable {
    /// The table of `camera` (which must have a distortion).
    pub fn new(camera: &Camera) -> RayTable {
        let (w, h) = (camera.width as usize, camera.height as usize);
        let d = camera.distortion.unwrap_or(Distortion {
            k1: 0.0,
            k2: 0.0,
            p1: 0.0,
            p2: 0.0,
            k3: 0.0,
        });
        let cells: Vec<([f64; 2], [f32; 4])> = (0..w * h)
            .into_par_iter()
            .map(|i| {
                let xd = ((i % w) as f64 - camera.cx) / camera.fx;
                let yd = ((i / w) as f64 - camera.cy) / camera.fy;
                let (x, y) = undistort_newton(&d, xd, yd);
                // Inverse of the distortion's Jacobian at (x, y), per pixel of offset.
                let (a, b, e) = distortion_jacobian(&d, x, y);
                let det = a * e - b * b;
                let (ia, ib, ie) = (e / det, -b / det, a / det);
                let j = [
                    ia / camera.fx,
                    ib / camera.fy,
                    ib / camera.fx,
                    ie / camera.fy,
                ];
                ([x, y], j.map(|v| v as f32))
            })
            .collect();
        RayTable {
            width: w,
            height: h,
            xy: cells.iter().map(|c| c.0).collect(),
            jacobian: cells.iter().map(|c| c.1).collect(),
        }
    }

    /// Ideal normalised coordinates of the ray through raw pixel (u, v).
    #[inline]
    pub fn ray(&self, camera: &Camera, u: f64, v: f64) -> (f64, f64) {
        let _ = camera;
        let iu = floor_index(u + 0.5).min(self.width - 1);
        let iv = floor_index(v + 0.5).min(self.height - 1);
        let (du, dv) = (u - iu as f64, v - iv as f64);
        let i = iv * self.width + iu;
        let [x, y] = self.xy[i];
        let j = self.jacobian[i];
        (
            x + j[0] as f64 * du + j[1] as f64 * dv,
            y + j[2] as f64 * du + j[3] as f64 * dv,
        )
    }
}

/// `x.floor().max(0.0) as usize` without the call to `floor` (the build targets plain SSE2,
/// which has no rounding instruction): truncation is the floor at and above zero, and
/// everything below zero (and NaN) gives 0 either way.
#[inline]
fn floor_index(x: f64) -> usize {
    if x > 0.0 {
        x as usize
    } else {
        0
    }
}

/// The ray table of a distorted camera, built once per process and camera.
fn ray_table(camera: &Camera) -> std::sync::Arc<RayTable> {
    use std::collections::HashMap;
    use std::sync::{Arc, Mutex, OnceLock};
    type Key = [u64; 11];
    static CACHE: OnceLock<Mutex<HashMap<Key, Arc<RayTable>>>> = OnceLock::new();
    let d = camera.distortion.unwrap_or(Distortion {
        k1: 0.0,
        k2: 0.0,
        p1: 0.0,
        p2: 0.0,
        k3: 0.0,
    });
    let key: Key = [
        camera.fx.to_bits(),
        camera.fy.to_bits(),
        camera.cx.to_bits(),
        camera.cy.to_bits(),
        camera.width as u64,
        camera.height as u64,
        d.k1.to_bits(),
        d.k2.to_bits(),
        d.p1.to_bits(),
        d.p2.to_bits(),
        d.k3.to_bits(),
    ];
    let cache = CACHE.get_or_init(Mutex::default);
    if let Some(t) = cache.lock().ok().and_then(|c| c.get(&key).cloned()) {
        return t;
    }
    let table = Arc::new(RayTable::new(camera));
    if let Ok(mut c) = cache.lock() {
        c.insert(key, table.clone());
    }
    table
}

/// The symmetric-off-diagonal Jacobian (d xd/dx, d xd/dy = d yd/dx, d yd/dy) of the
/// radial-tangential distortion at ideal normalised (x, y).
#[inline]
fn distortion_jacobian(d: &Distortion, x: f64, y: f64) -> (f64, f64, f64) {
    let r2 = x * x + y * y;
    let radial = 1.0 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
    let dradial = d.k1 + r2 * (2.0 * d.k2 + 3.0 * r2 * d.k3);
    let a = radial + 2.0 * x * x * dradial + 2.0 * d.p1 * y + 6.0 * d.p2 * x;
    let b = 2.0 * x * y * dradial + 2.0 * d.p1 * x + 2.0 * d.p2 * y;
    let e = radial + 2.0 * y * y * dradial + 6.0 * d.p1 * y + 2.0 * d.p2 * x;
    (a, b, e)
}

/// The ideal normalised coordinates whose radial-tangential distortion is (xd, yd): Newton's
/// method on the 2x2 Jacobian of the distortion, from (xd, yd); converged to about 1e-15 in
/// three to five steps for the TUM and EuRoC lenses (the fixed-point iteration of
/// `Camera::undistort_point` needs about twenty, which made distorted renders twice as slow).
#[inline]
pub fn undistort_newton(d: &Distortion, xd: f64, yd: f64) -> (f64, f64) {
    let (mut x, mut y) = (xd, yd);
    for _ in 0..8 {
        let (px, py) = slam_core::camera::distort_normalized(d, x, y);
        let (fx, fy) = (px - xd, py - yd);
        let (a, b, e) = distortion_jacobian(d, x, y);
        let det = a * e - b * b;
        if det.abs() < 1e-12 {
            break;
        }
        let (sx, sy) = ((e * fx - b * fy) / det, (a * fy - b * fx) / det);
        x -= sx;
        y -= sy;
        if sx.abs() < 1e-15 && sy.abs() < 1e-15 {
            break;
        }
    }
    (x, y)
}

/// The raw-image bounds of an ideal-pixel box: the box is clipped to a margin around the image
/// (where the distortion polynomial is monotone), its boundary distorted at 32 points per
/// edge, and the extremes widened by 2 pixels. A box that misses the clipped region maps to an
/// empty (inverted) box; an unbounded one stays unbounded.
fn distort_bounds(camera: &Camera, b: [f64; 4]) -> [f64; 4] {
    if b.iter().any(|x| !x.is_finite()) {
        return b;
    }
    let (w, h) = (camera.width as f64, camera.height as f64);
    let (mu, mv) = (0.25 * w, 0.25 * h);
    let u0 = b[0].max(-mu);
    let u1 = b[1].min(w + mu);
    let v0 = b[2].max(-mv);
    let v1 = b[3].min(h + mv);
    if u0 > u1 || v0 > v1 {
        return [1.0, 0.0, 1.0, 0.0];
    }
    let mut out = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    const N: usize = 32;
    for i in 0..=N {
        let a = i as f64 / N as f64;
        let (u, v) = (u0 + a * (u1 - u0), v0 + a * (v1 - v0));
        for (x, y) in [(u, v0), (u, v1), (u0, v), (u1, v)] {
            let (xd, yd) = camera.distort_point(x, y);
            out[0] = out[0].min(xd);
            out[1] = out[1].max(xd);
            out[2] = out[2].min(yd);
            out[3] = out[3].max(yd);
        }
    }
    // A box clipped at the margin may reach beyond it: keep it open on that side.
    if b[0] < -mu {
        out[0] = f64::NEG_INFINITY;
    }
    if b[1] > w + mu {
        out[1] = f64::INFINITY;
    }
    if b[2] < -mv {
        out[2] = f64::NEG_INFINITY;
    }
    if b[3] > h + mv {
        out[3] = f64::INFINITY;
    }
    [out[0] - 2.0, out[1] + 2.0, out[2] - 2.0, out[3] + 2.0]
}

/// A colour image exposed over time: where the camera and the objects are at any instant.
pub struct Exposed<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Intrinsics, image size and lens distortion.
    pub camera: &'a Camera,
    /// Camera-to-world pose at a time (seconds since frame 0).
    pub pose_at: &'a (dyn Fn(f64) -> Isometry3<f64> + Sync),
    /// Whether the featureless occluder covers the lens.
    pub occluded: bool,
    /// Time of the stamp (middle of the exposure of the middle row), seconds since frame 0.
    pub time: f64,
    /// Exposure time, seconds (0: a snapshot per row).
    pub exposure_s: f64,
    /// Rolling-shutter readout time from the first to the last row, seconds (0: global).
    pub readout_s: f64,
    /// Time samples per pixel (>= 1), each with its own sub-pixel ray.
    pub samples: usize,
    /// Shading.
    pub shading: Shading,
}

impl Exposed<'_> {
    /// Renders the colour image: each pixel averages `samples` rays, sample `k` of row `v` cast
    /// at [`crate::sensor::imaging::sample_offset`] inside the pixel and at the instant
    /// `time + row_time(v) + sample_time(k)`, with the camera and the objects where they are at
    /// that instant.
    pub fn render(&self) -> Vec<[f32; 3]> {
        use crate::sensor::imaging::{row_time, sample_offset, sample_time};
        let (w, h) = (self.camera.width as usize, self.camera.height as usize);
        let n = self.samples.max(1);
        let inv = 1.0 / n as f32;
        let bounds = self.frame_bounds();
        let b = &bounds;
        // The static objects are where they are at any instant: placed once, and only the
        // moving ones placed again per row and sample.
        let base = self.scene.place(self.time);
        let rays = self.camera.distortion.map(|_| ray_table(self.camera));
        let rays = rays.as_deref();
        // Each sample's instant, pose and objects as the first row sees them: the rows of a
        // global shutter share them (their instants are equal to the bit), so they are worked
        // out once a frame instead of once a row.
        let t0 = self.time + row_time(0.0, h, self.readout_s);
        let shared: Vec<Instant> = (0..n)
            .map(|k| Instant::at(self, t0 + sample_time(k, n, self.exposure_s), &base))
            .collect();
        let (base, shared) = (&base, &shared);
        let mut out = vec![[0.0f32; 3]; w * h];
        out.par_chunks_mut(w).enumerate().for_each_init(
            || None::<Instant>,
            |own, (v, acc)| {
                let t_row = self.time + row_time(v as f64, h, self.readout_s);
                for (k, first) in shared.iter().enumerate() {
                    let t = t_row + sample_time(k, n, self.exposure_s);
                    let at = if first.t.to_bits() == t.to_bits() {
                        first
                    } else {
                        match own {
                            Some(i) => i.move_to(self, t, base),
                            None => *own = Some(Instant::at(self, t, base)),
                        }
                        own.as_ref().expect("set just above")
                    };
                    let view = View {
                        scene: self.scene,
                        placed: &at.placed,
                        camera: self.camera,
                        pose_wc: at.pose_wc,
                        occluded: self.occluded,
                    };
                    let (dx, dy) = sample_offset(k, n);
                    view.row(
                        rays,
                        &at.seen,
                        b,
                        dx,
                        v as f64 + dy,
                        w,
                        Some(&self.shading),
                        |u, s| {
                            for (ak, ck) in acc[u].iter_mut().zip(s.colour) {
                                *ak += ck;
                            }
                        },
                    );
                }
                for a in acc.iter_mut() {
                    *a = a.map(|x| x * inv);
                }
            },
        );
        out
    }

    /// Image bounds of each object valid over the whole frame (all rows, the whole exposure):
    /// the union of its bounds at [`FRAME_BOUND_INSTANTS`] instants spanning the frame, widened
    /// by [`FRAME_BOUND_MARGIN_PX`] for the motion between them. Computing bounds per row and
    /// time sample instead cost more than the rays when the lens is distorted.
    fn frame_bounds(&self) -> Vec<[f64; 4]> {
        let span = 0.5 * (self.readout_s + self.exposure_s);
        let mut out: Option<Vec<[f64; 4]>> = None;
        for i in 0..FRAME_BOUND_INSTANTS {
            let a = i as f64 / (FRAME_BOUND_INSTANTS - 1) as f64;
            let t = self.time - span + 2.0 * span * a;
            let placed = self.scene.place(t);
            let b = View {
                scene: self.scene,
                placed: &placed,
                camera: self.camera,
                pose_wc: (self.pose_at)(t),
                occluded: self.occluded,
            }
            .screen_bounds();
            out = Some(match out {
                None => b,
                Some(o) => o.iter().zip(&b).map(|(p, q)| union_bounds(p, q)).collect(),
            });
        }
        let m = FRAME_BOUND_MARGIN_PX;
        out.unwrap_or_default()
            .into_iter()
            .map(|b| {
                if b[0] > b[1] || b[2] > b[3] {
                    b
                } else {
                    [b[0] - m, b[1] + m, b[2] - m, b[3] + m]
                }
            })
            .collect()
    }
}

/// An instant of an [`Exposed`] render: the camera pose and the objects placed and seen from
/// the camera centre then.
struct Instant {
    /// Seconds since frame 0.
    t: f64,
    pose_wc: Isometry3<f64>,
    placed: Vec<Placed>,
    seen: Vec<Seen>,
}

impl Instant {
    /// The instant `t` of `exposed`, its objects moved from `base` ([`Scene::place`] at any
    /// time).
    fn at(exposed: &Exposed, t: f64, base: &[Placed]) -> Instant {
        let mut i = Instant {
            t,
            pose_wc: Isometry3::identity(),
            placed: Vec::new(),
            seen: Vec::new(),
        };
        i.move_to(exposed, t, base);
        i
    }

    /// Makes this the instant `t` (reusing its buffers).
    fn move_to(&mut self, exposed: &Exposed, t: f64, base: &[Placed]) {
        self.t = t;
        self.pose_wc = (exposed.pose_at)(t);
        self.placed.clear();
        self.placed.extend_from_slice(base);
        exposed.scene.place_moving(t, &mut self.placed);
        View {
            scene: exposed.scene,
            placed: &self.placed,
            camera: exposed.camera,
            pose_wc: self.pose_wc,
            occluded: exposed.occluded,
        }
        .seen_into(&mut self.seen);
    }
}

/// Instants at which [`Exposed`] samples object bounds over a frame.
const FRAME_BOUND_INSTANTS: usize = 7;
/// Margin added to those bounds for the motion between the instants, pixels.
const FRAME_BOUND_MARGIN_PX: f64 = 3.0;

/// The smallest box holding two boxes; an empty (inverted) box holds nothing.
fn union_bounds(p: &[f64; 4], q: &[f64; 4]) -> [f64; 4] {
    let empty = |b: &[f64; 4]| b[0] > b[1] || b[2] > b[3];
    match (empty(p), empty(q)) {
        (true, _) => *q,
        (_, true) => *p,
        _ => [
            p[0].min(q[0]),
            p[1].max(q[1]),
            p[2].min(q[2]),
            p[3].max(q[3]),
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::trajectory::{pose_at, Trajectory};

    /// The ray table's first-order step agrees with the exact inverse between pixel centres.
    #[test]
    fn ray_table_matches_newton_between_pixel_centres() {
        let cam = Camera::tum_fr1();
        let d = cam.distortion.unwrap();
        let table = RayTable::new(&cam);
        let mut worst = 0.0f64;
        for v in (0..480).step_by(13) {
            for u in (0..640).step_by(11) {
                for (du, dv) in [(0.0, 0.0), (0.49, -0.3), (-0.5, 0.5), (0.25, 0.1)] {
                    let (uu, vv) = (u as f64 + du, v as f64 + dv);
                    let (x, y) = table.ray(&cam, uu, vv);
                    let (ex, ey) =
                        undistort_newton(&d, (uu - cam.cx) / cam.fx, (vv - cam.cy) / cam.fy);
                    worst = worst.max(((x - ex) * cam.fx).hypot((y - ey) * cam.fy));
                }
            }
        }
        assert!(worst < 1e-3, "worst {worst} px");
    }

    /// Newton's undistortion inverts the distortion over the whole fr1 / fr2 image and beyond.
    #[test]
    fn newton_undistortion_inverts_the_distortion() {
        for cam in [Camera::tum_fr1(), Camera::tum_fr2()] {
            let d = cam.distortion.unwrap();
            for v in (-40..=520).step_by(20) {
                for u in (-40..=680).step_by(20) {
                    let (xd, yd) = ((u as f64 - cam.cx) / cam.fx, (v as f64 - cam.cy) / cam.fy);
                    let (x, y) = undistort_newton(&d, xd, yd);
                    let (rx, ry) = slam_core::camera::distort_normalized(&d, x, y);
                    assert!(
                        (rx - xd).abs() < 1e-12 && (ry - yd).abs() < 1e-12,
                        "{u},{v}"
                    );
                    if cam.in_image(u as f64, v as f64) {
                        let (uu, vu) = cam.undistort_point(u as f64, v as f64);
                        assert!((x * cam.fx + cam.cx - uu).abs() < 1e-6);
                        assert!((y * cam.fy + cam.cy - vu).abs() < 1e-6);
                    }
                }
            }
        }
    }

    /// The cone of a segment's camera-frame box holds every ray of the segment, turned into
    /// the world, with the margin to spare (the cone test culls nothing any ray could hit).
    #[test]
    fn segment_cone_holds_its_rays() {
        let cam = Camera::tum_fr1();
        let table = RayTable::new(&cam);
        for (k, v) in [0.0, 11.3, 239.5, 479.0].into_iter().enumerate() {
            let pose = pose_at(&Trajectory::Xyz, 0.37 * k as f64);
            for x0 in [-0.5, 0.0, 300.25, 624.0] {
                let dcs: Vec<Vector3<f64>> = (0..16)
                    .map(|j| {
                        let (x, y) = table.ray(&cam, x0 + j as f64, v);
                        Vector3::new(x, y, 1.0)
                    })
                    .collect();
                let cone = RayCone::of_camera(dcs.iter(), &pose.rotation);
                for dc in &dcs {
                    let d = pose.rotation * dc;
                    let cos = cone.axis.dot(&d) / d.norm();
                    assert!(cos >= cone.cos + 0.5 * CONE_MARGIN, "{v} {x0}");
                }
            }
        }
    }

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
            pose_wc: pose_at(&Trajectory::Xyz, 0.0),
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
