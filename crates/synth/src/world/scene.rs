//! The indoor scene: a textured room (floor, ceiling, four walls) with the furniture of a
//! [`crate::world::layout::Layout`] standing in front of each other (so depth boundaries are common,
//! the paper's Fig. 2), and optional walking "people" (articulated bodies, or textured boxes /
//! cylinders).
//!
//! World frame: x, y horizontal, z up, metres; the presets' office spans x, y in [-2.5, 2.5],
//! z in [0, 2.7] with fixed furniture (so every trajectory sees textured content within sensor
//! range); the twins' rooms are drawn from the seed ([`crate::world::layout`]). The textures are drawn
//! from a `ChaCha8Rng` seeded with the sequence seed.

use nalgebra::Vector3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::world::layout::{layout, Layout, RoomBox, SceneSpec};
use crate::world::people::{self, part_shapes, Activity, PartPose, Person, CHAIRS};
use crate::world::shape::Shape;
use crate::world::texture::{Style, Texture};

/// Object id of the featureless occluder of the occlusion window.
pub const OCCLUDER_ID: u16 = u16::MAX;
/// Object ids of the chairs of scenes with people (static, after the fixed furniture).
pub const CHAIR_ID_BASE: u16 = 900;
/// Object ids at or above this (and below [`OCCLUDER_ID`]) are moving objects.
pub const MOVING_ID_BASE: u16 = 1000;

/// Independently moving textured objects ("people", like fr3_walking).
#[derive(Clone, Debug, PartialEq)]
pub struct MovingObjects {
    /// How many (1..=3; default 2).
    pub count: usize,
    /// Walking speed multiplier (default 1; 1 is about 0.4-0.6 m/s). Not used by bodies.
    pub speed: f64,
    /// Articulated people doing this instead of the textured blocks (count 1..=2), with the
    /// desk's chairs (default `None`: blocks, as the `walking` preset has always had).
    pub bodies: Option<Activity>,
}

impl Default for MovingObjects {
    fn default() -> Self {
        MovingObjects {
            count: 2,
            speed: 1.0,
            bodies: None,
        }
    }
}

/// Back-and-forth walk of a moving object: centre(t) = centre + axis * amplitude *
/// sin(2 pi t / period + phase) + perpendicular * sway * sin(4 pi t / period + phase).
#[derive(Clone, Copy, Debug)]
pub struct Walk {
    /// Unit walking direction in the floor plane.
    pub axis: [f64; 2],
    /// Amplitude along the axis, metres.
    pub amplitude: f64,
    /// Period of one back-and-forth, seconds.
    pub period: f64,
    /// Phase, radians.
    pub phase: f64,
    /// Sideways sway amplitude, metres.
    pub sway: f64,
}

/// A textured object of the scene.
#[derive(Clone, Debug)]
pub struct Object {
    /// Geometry in the local frame.
    pub shape: Shape,
    /// Centre of the local frame in the world at rest, metres.
    pub centre: [f64; 3],
    /// Rotation about the vertical, radians.
    pub yaw: f64,
    /// Index into the scene's textures.
    pub texture: usize,
    /// Object id written into the id buffer.
    pub id: u16,
    /// Motion, for moving objects.
    pub walk: Option<Walk>,
    /// A body part: (person, part) into `Scene::people` and [`crate::world::people::PARTS`].
    pub body: Option<(usize, usize)>,
}

impl Object {
    /// Whether the object moves (a walking block or a body part).
    pub fn moves(&self) -> bool {
        self.walk.is_some() || self.body.is_some()
    }
}

/// An object placed at a given time: what the ray-caster intersects.
#[derive(Clone, Copy, Debug)]
pub struct Placed {
    /// Index into `Scene::objects`.
    pub object: usize,
    /// World position of the centre.
    pub centre: Vector3<f64>,
    cos_yaw: f64,
    sin_yaw: f64,
    /// Swing about the local y axis after the yaw (body parts; `None` for everything else,
    /// whose rays then take exactly the arithmetic they always took).
    pitch: Option<(f64, f64)>,
    /// Bounding-sphere radius.
    pub radius: f64,
}

impl Placed {
    /// World offset `r` (from the centre) into the object's local frame.
    #[inline]
    fn world_to_local(&self, r: &Vector3<f64>) -> Vector3<f64> {
        let (c, s) = (self.cos_yaw, self.sin_yaw);
        let l = Vector3::new(c * r.x + s * r.y, -s * r.x + c * r.y, r.z);
        match self.pitch {
            None => l,
            Some((cp, sp)) => Vector3::new(cp * l.x + sp * l.z, l.y, -sp * l.x + cp * l.z),
        }
    }

    /// Local direction `n` back into the world.
    #[inline]
    fn local_to_world(&self, n: &Vector3<f64>) -> Vector3<f64> {
        let n = match self.pitch {
            None => *n,
            Some((cp, sp)) => Vector3::new(cp * n.x - sp * n.z, n.y, sp * n.x + cp * n.z),
        };
        let (c, s) = (self.cos_yaw, self.sin_yaw);
        Vector3::new(c * n.x - s * n.y, s * n.x + c * n.y, n.z)
    }
}

/// A placed object as seen from a camera centre ([`Scene::seen_from`]).
#[derive(Clone, Copy, Debug)]
pub struct Seen {
    placed: Placed,
    /// Centre minus camera centre.
    oc: Vector3<f64>,
    /// `oc . oc`.
    oc2: f64,
    /// Bounding radius squared.
    r2: f64,
    /// The camera centre in the object's local frame.
    lo: Vector3<f64>,
    /// Cuboid: per axis, the faces' offsets from `lo` (-half - lo, half - lo). Cylinder:
    /// [lo.x^2 + lo.y^2 - r^2, _], [hh - lo.z, -hh - lo.z].
    slabs: [[f64; 2]; 3],
}

impl Seen {
    /// The placed object.
    pub fn placed(&self) -> &Placed {
        &self.placed
    }

    /// Its centre relative to the camera centre.
    pub fn oc(&self) -> &Vector3<f64> {
        &self.oc
    }

    /// Squared distance of its centre from the camera centre.
    pub fn oc2(&self) -> f64 {
        self.oc2
    }
}

/// Result of a ray hit.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter (for rays with unit z in camera coordinates: the z-depth), metres.
    pub t: f64,
    /// Unit world normal on the side the ray came from.
    pub normal: Vector3<f64>,
    /// Texture index.
    pub texture: usize,
    /// Surface coordinates for the texture, metres.
    pub st: (f64, f64),
    /// Object id.
    pub id: u16,
}

/// The room, its objects and their textures.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Objects (static and moving).
    pub objects: Vec<Object>,
    /// Textures: six room faces first (floor, ceiling, -x, +x, -y, +y), then one per object.
    pub textures: Vec<Texture>,
    /// Point light position (world, metres).
    pub light: Vector3<f64>,
    /// Articulated people (their parts are objects with `body` set).
    pub people: Vec<Person>,
    /// The room's box.
    pub room: RoomBox,
}

/// Margin added to a body part's bounding sphere, metres (a foot moves up to ~4 m/s, 3 cm
/// between the renderer's bound samples).
const BODY_BOUND_MARGIN: f64 = 0.05;

/// The desk's chairs ([`CHAIRS`]): a seat block and a backrest each, only in
/// scenes with people (the other scenes keep their layout).
fn add_chairs(objects: &mut Vec<Object>, textures: &mut Vec<Texture>, rng: &mut ChaCha8Rng) {
    for (k, chair) in CHAIRS.iter().enumerate() {
        let (cy, sy) = (chair.yaw.cos(), chair.yaw.sin());
        let back = [chair.at[0] - 0.2 * cy, chair.at[1] - 0.2 * sy];
        let parts = [
            (
                Shape::Cuboid {
                    half: [0.21, 0.21, 0.225],
                },
                [chair.at[0], chair.at[1], 0.225],
            ),
            (
                Shape::Cuboid {
                    half: [0.025, 0.21, 0.26],
                },
                [back[0], back[1], 0.45 + 0.26],
            ),
        ];
        for (j, (shape, centre)) in parts.into_iter().enumerate() {
            let (tw, th) = shape.texture_size();
            textures.push(Texture::collage(rng, tw, th, 0.0025, Style::Cloth));
            objects.push(Object {
                shape,
                centre,
                yaw: chair.yaw,
                texture: textures.len() - 1,
                id: CHAIR_ID_BASE + (2 * k + j) as u16,
                walk: None,
                body: None,
            });
        }
    }
}

impl Scene {
    /// Builds the fixed office with textures drawn from `seed`, plus `moving` walking objects.
    pub fn new(seed: u64, moving: Option<&MovingObjects>) -> Scene {
        let people = moving.is_some_and(|m| m.bodies.is_some());
        Scene::with_layout(
            seed,
            moving,
            &layout(&SceneSpec::default(), seed, &[], people),
        )
    }

    /// Builds `layout`'s room and furniture with textures drawn from `seed`, plus `moving`
    /// walking objects.
    pub fn with_layout(seed: u64, moving: Option<&MovingObjects>, layout: &Layout) -> Scene {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5CE4_E5EE_D000_0001);
        let room = layout.room;
        let [hx, hy] = room.half;
        let texel = layout.face_texel_m;
        let f = &layout.faces;
        let mut textures = vec![
            Texture::collage(&mut rng, 2.0 * hx, 2.0 * hy, texel, f[0]),
            Texture::collage(&mut rng, 2.0 * hx, 2.0 * hy, texel.max(0.01), f[1]),
        ];
        for (k, style) in f[2..].iter().enumerate() {
            let width = if k < 2 { 2.0 * hy } else { 2.0 * hx };
            textures.push(Texture::collage(
                &mut rng,
                width,
                room.height,
                texel,
                *style,
            ));
        }
        let mut objects = Vec::new();
        for (i, o) in layout.objects.iter().enumerate() {
            let (tw, th) = o.shape.texture_size();
            textures.push(Texture::collage(&mut rng, tw, th, 0.0025, o.style));
            objects.push(Object {
                shape: o.shape,
                centre: o.centre,
                yaw: o.yaw,
                texture: textures.len() - 1,
                id: 10 + i as u16,
                walk: None,
                body: None,
            });
        }
        let mut people = Vec::new();
        if let Some(activity) = moving.and_then(|m| m.bodies) {
            let count = moving.map_or(0, |m| m.count);
            people = people::people(seed, count, activity);
            add_chairs(&mut objects, &mut textures, &mut rng);
            let shapes = part_shapes();
            for p in 0..people.len() {
                // One texture each part, of the part's size: cloth, the head a face.
                for (k, shape) in shapes.iter().enumerate() {
                    let (tw, th) = shape.texture_size();
                    let style = if k == 1 { Style::Head } else { Style::Cloth };
                    textures.push(Texture::collage(&mut rng, tw, th, 0.0025, style));
                    objects.push(Object {
                        shape: *shape,
                        centre: [0.0; 3],
                        yaw: 0.0,
                        texture: textures.len() - 1,
                        id: MOVING_ID_BASE + (p * shapes.len() + k) as u16,
                        walk: None,
                        body: Some((p, k)),
                    });
                }
            }
        } else if let Some(m) = moving {
            let people = [
                // In front of the table, crossing the view at about 1 m from the camera.
                (
                    Shape::Cylinder {
                        radius: 0.22,
                        half_height: 0.85,
                    },
                    [0.0, 0.22, 0.85],
                    Walk {
                        axis: [1.0, 0.0],
                        amplitude: 0.85,
                        period: 9.0,
                        phase: 0.3,
                        sway: 0.08,
                    },
                ),
                // Behind the table.
                (
                    Shape::Cuboid {
                        half: [0.24, 0.15, 0.85],
                    },
                    [0.0, 2.02, 0.85],
                    Walk {
                        axis: [1.0, 0.0],
                        amplitude: 0.8,
                        period: 7.0,
                        phase: 2.0,
                        sway: 0.05,
                    },
                ),
                // Diagonally across, left of the table.
                (
                    Shape::Cuboid {
                        half: [0.2, 0.2, 0.8],
                    },
                    [-1.05, 1.0, 0.8],
                    Walk {
                        axis: [0.3, 0.954],
                        amplitude: 0.6,
                        period: 11.0,
                        phase: 4.0,
                        sway: 0.05,
                    },
                ),
            ];
            for (k, (shape, centre, walk)) in people.iter().take(m.count).enumerate() {
                let (tw, th) = shape.texture_size();
                textures.push(Texture::collage(&mut rng, tw, th, 0.0025, Style::Poster));
                objects.push(Object {
                    shape: *shape,
                    centre: *centre,
                    yaw: 0.0,
                    texture: textures.len() - 1,
                    id: MOVING_ID_BASE + k as u16,
                    walk: Some(Walk {
                        period: walk.period / m.speed.max(1e-6),
                        ..*walk
                    }),
                    body: None,
                });
            }
        }
        Scene {
            objects,
            textures,
            light: layout.light,
            people,
            room,
        }
    }

    /// The objects placed at time `t` seconds.
    pub fn place(&self, t: f64) -> Vec<Placed> {
        let bodies = self.body_poses(t);
        self.objects
            .iter()
            .enumerate()
            .map(|(i, o)| self.place_object(i, o, t, &bodies))
            .collect()
    }

    /// Moves the moving objects of `placed` (objects placed by [`Scene::place`] at any time)
    /// to time `t`: the same placement as `place(t)`, without recomputing the static objects,
    /// whose placement does not depend on the time.
    pub fn place_moving(&self, t: f64, placed: &mut [Placed]) {
        let bodies = self.body_poses(t);
        for (i, (o, p)) in self.objects.iter().zip(placed).enumerate() {
            if o.moves() {
                *p = self.place_object(i, o, t, &bodies);
            }
        }
    }

    /// The poses of the people's parts at `t`.
    fn body_poses(&self, t: f64) -> Vec<[PartPose; 8]> {
        self.people.iter().map(|p| p.pose(t)).collect()
    }

    /// Object `i` (`o`) placed at `t`, its person's parts at `bodies` when it is a body part.
    #[inline]
    fn place_object(&self, i: usize, o: &Object, t: f64, bodies: &[[PartPose; 8]]) -> Placed {
        if let Some((p, k)) = o.body {
            let q = bodies[p][k];
            return Placed {
                object: i,
                centre: q.centre,
                cos_yaw: q.yaw.cos(),
                sin_yaw: q.yaw.sin(),
                pitch: Some((q.pitch.cos(), q.pitch.sin())),
                // Limbs move fast: the margin keeps each part inside the bounds that
                // the renderer samples a few times per frame.
                radius: o.shape.bound() + BODY_BOUND_MARGIN,
            };
        }
        let mut c = Vector3::new(o.centre[0], o.centre[1], o.centre[2]);
        if let Some(w) = &o.walk {
            let a = std::f64::consts::TAU * t / w.period + w.phase;
            let along = w.amplitude * a.sin();
            let side = w.sway * (2.0 * a).sin();
            c.x += w.axis[0] * along - w.axis[1] * side;
            c.y += w.axis[1] * along + w.axis[0] * side;
        }
        Placed {
            object: i,
            centre: c,
            cos_yaw: o.yaw.cos(),
            sin_yaw: o.yaw.sin(),
            pitch: None,
            radius: o.shape.bound(),
        }
    }

    /// Nearest hit of the ray o + t d (t > 0) with the room and the placed objects.
    pub fn intersect(&self, placed: &[Placed], o: &Vector3<f64>, d: &Vector3<f64>) -> Hit {
        let seen: Vec<Seen> = placed.iter().map(|p| self.seen_from(p, o)).collect();
        self.intersect_seen(&seen, o, d)
    }

    /// `p` as the rays from camera centre `o` meet it: what their tests need that depends on
    /// the object and `o` only, computed once per view.
    pub fn seen_from(&self, p: &Placed, o: &Vector3<f64>) -> Seen {
        let oc = p.centre - o;
        // Into the local frame: translate, then rotate by -yaw about z (and -pitch).
        let lo = p.world_to_local(&-oc);
        let obj = &self.objects[p.object];
        let slabs = match obj.shape {
            Shape::Cuboid { half } => [
                [-half[0] - lo[0], half[0] - lo[0]],
                [-half[1] - lo[1], half[1] - lo[1]],
                [-half[2] - lo[2], half[2] - lo[2]],
            ],
            Shape::Cylinder {
                radius,
                half_height,
            } => [
                [lo.x * lo.x + lo.y * lo.y - radius * radius, 0.0],
                [half_height - lo.z, -half_height - lo.z],
                [0.0; 2],
            ],
        };
        Seen {
            placed: *p,
            oc,
            oc2: oc.dot(&oc),
            r2: p.radius * p.radius,
            lo,
            slabs,
        }
    }

    /// [`Scene::intersect`] of objects prepared by [`Scene::seen_from`] for camera centre `o`:
    /// the same arithmetic on the same values, the ray-independent part done once.
    #[inline]
    pub fn intersect_seen(&self, seen: &[Seen], o: &Vector3<f64>, d: &Vector3<f64>) -> Hit {
        let mut best = room_hit(&self.room, o, d);
        if seen.is_empty() {
            return best;
        }
        let dd = d.dot(d);
        let inv_len = 1.0 / dd.sqrt();
        for s in seen {
            let p = &s.placed;
            let tca = s.oc.dot(d) / dd;
            let dist2 = s.oc2 - tca * tca * dd;
            if dist2 > s.r2 || tca + p.radius * inv_len < 0.0 {
                continue;
            }
            if tca - p.radius * inv_len > best.t {
                continue;
            }
            let obj = &self.objects[p.object];
            let ld = p.world_to_local(d);
            let local = match obj.shape {
                Shape::Cuboid { half } => hit_cuboid(&s.lo, &ld, &half, &s.slabs),
                Shape::Cylinder {
                    radius,
                    half_height,
                } => hit_cylinder(&s.lo, &ld, radius, half_height, &s.slabs),
            };
            if let Some((t, n, st)) = local {
                if t < best.t {
                    // Normal back to the world.
                    let nw = p.local_to_world(&n);
                    best = Hit {
                        t,
                        normal: nw,
                        texture: obj.texture,
                        st,
                        id: obj.id,
                    };
                }
            }
        }
        best
    }

    /// Unsigned distance (metres) from world point `q` to the nearest surface of the room or
    /// of a placed object: an independent check of the ray-caster used by tests.
    pub fn surface_distance(&self, placed: &[Placed], q: &Vector3<f64>) -> f64 {
        let [hx, hy] = self.room.half;
        let mut best = (q.x + hx)
            .abs()
            .min((hx - q.x).abs())
            .min((q.y + hy).abs())
            .min((hy - q.y).abs())
            .min(q.z.abs())
            .min((self.room.height - q.z).abs());
        for p in placed {
            let l = p.world_to_local(&(q - p.centre));
            let sdf = self.objects[p.object].shape.signed_distance(&l);
            best = best.min(sdf.abs());
        }
        best
    }
}

/// Exit of the ray from the inside of the room box.
#[inline]
fn room_hit(room: &RoomBox, o: &Vector3<f64>, d: &Vector3<f64>) -> Hit {
    let [hx, hy] = room.half;
    let lo = [-hx, -hy, 0.0];
    let hi = [hx, hy, room.height];
    let mut best_t = f64::INFINITY;
    let mut face = 0usize;
    for a in 0..3 {
        if d[a] > 0.0 {
            let t = (hi[a] - o[a]) / d[a];
            if t < best_t {
                best_t = t;
                face = 2 * a + 1;
            }
        } else if d[a] < 0.0 {
            let t = (lo[a] - o[a]) / d[a];
            if t < best_t {
                best_t = t;
                face = 2 * a;
            }
        }
    }
    let p = o + d * best_t;
    // face: 0 -x, 1 +x, 2 -y, 3 +y, 4 floor, 5 ceiling.
    let (normal, texture, st) = match face {
        0 => (Vector3::x(), 2, (p.y + hy, p.z)),
        1 => (-Vector3::x(), 3, (hy - p.y, p.z)),
        2 => (Vector3::y(), 4, (hx - p.x, p.z)),
        3 => (-Vector3::y(), 5, (p.x + hx, p.z)),
        4 => (Vector3::z(), 0, (p.x + hx, p.y + hy)),
        _ => (-Vector3::z(), 1, (p.x + hx, p.y + hy)),
    };
    Hit {
        t: best_t,
        normal,
        texture,
        st,
        id: 1 + face as u16,
    }
}

/// Ray / box slab test in the box's local frame; entry hit only (the camera is never inside).
/// `slabs[a]` = (-half[a] - o[a], half[a] - o[a]).
#[inline]
fn hit_cuboid(
    o: &Vector3<f64>,
    d: &Vector3<f64>,
    half: &[f64; 3],
    slabs: &[[f64; 2]; 3],
) -> Option<(f64, Vector3<f64>, (f64, f64))> {
    let mut t_near = f64::NEG_INFINITY;
    let mut t_far = f64::INFINITY;
    let mut axis = 0;
    for a in 0..3 {
        if d[a].abs() < 1e-15 {
            if o[a].abs() > half[a] {
                return None;
            }
            continue;
        }
        let inv = 1.0 / d[a];
        let mut t0 = slabs[a][0] * inv;
        let mut t1 = slabs[a][1] * inv;
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        if t0 > t_near {
            t_near = t0;
            axis = a;
        }
        t_far = t_far.min(t1);
    }
    if t_near > t_far || t_near <= 1e-9 {
        return None;
    }
    let p = o + d * t_near;
    let sign = if d[axis] > 0.0 { -1.0 } else { 1.0 };
    let mut n = Vector3::zeros();
    n[axis] = sign;
    // Face coordinates, shifted per face so that faces do not repeat each other.
    let face = (2 * axis + (sign > 0.0) as usize) as f64;
    let (u, v) = match axis {
        0 => (p.y + half[1], p.z + half[2]),
        1 => (p.x + half[0], p.z + half[2]),
        _ => (p.x + half[0], p.y + half[1]),
    };
    Some((t_near, n, (u + 0.37 * face, v + 0.23 * face)))
}

/// Ray / vertical cylinder (with caps) in the cylinder's local frame.
#[inline]
/// `slabs[0][0]` = o.x^2 + o.y^2 - r^2; `slabs[1]` = (hh - o.z, -hh - o.z).
fn hit_cylinder(
    o: &Vector3<f64>,
    d: &Vector3<f64>,
    r: f64,
    hh: f64,
    slabs: &[[f64; 2]; 3],
) -> Option<(f64, Vector3<f64>, (f64, f64))> {
    let mut best: Option<(f64, Vector3<f64>, (f64, f64))> = None;
    let a = d.x * d.x + d.y * d.y;
    if a > 1e-15 {
        let b = o.x * d.x + o.y * d.y;
        let c = slabs[0][0];
        let disc = b * b - a * c;
        if disc >= 0.0 {
            let t = (-b - disc.sqrt()) / a;
            if t > 1e-9 {
                let p = o + d * t;
                if p.z.abs() <= hh {
                    let ang = p.y.atan2(p.x);
                    best = Some((
                        t,
                        Vector3::new(p.x / r, p.y / r, 0.0),
                        ((ang + std::f64::consts::PI) * r, p.z + hh),
                    ));
                }
            }
        }
    }
    if d.z.abs() > 1e-15 {
        let (zc, dz) = if d.z < 0.0 {
            (hh, slabs[1][0])
        } else {
            (-hh, slabs[1][1])
        };
        let t = dz / d.z;
        if t > 1e-9 && best.is_none_or(|b| t < b.0) {
            let p = o + d * t;
            if p.x * p.x + p.y * p.y <= r * r {
                best = Some((
                    t,
                    Vector3::new(0.0, 0.0, zc.signum()),
                    (p.x + r + 0.31, p.y + r + 0.17),
                ));
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::layout::furniture_clearance;

    #[test]
    fn ray_hits_lie_on_surfaces() {
        let scene = Scene::new(3, Some(&MovingObjects::default()));
        let placed = scene.place(1.3);
        let o = Vector3::new(0.1, -0.6, 1.4);
        let mut n_obj = 0;
        for i in 0..400 {
            let a = i as f64 * 0.7;
            let d = Vector3::new(a.cos() * 0.8, 1.0, (a * 1.3).sin() * 0.7 - 0.3);
            let h = scene.intersect(&placed, &o, &d);
            let p = o + d * h.t;
            assert!(scene.surface_distance(&placed, &p) < 1e-9, "ray {i}");
            assert!(h.normal.dot(&d) <= 1e-12, "normal faces the ray");
            n_obj += (h.id >= 10) as usize;
        }
        assert!(n_obj > 50, "objects are in front of the camera: {n_obj}");
    }

    #[test]
    fn moving_objects_move_and_statics_stay() {
        let scene = Scene::new(1, Some(&MovingObjects::default()));
        let a = scene.place(0.0);
        let b = scene.place(1.0);
        for (pa, pb) in a.iter().zip(&b) {
            let moved = (pa.centre - pb.centre).norm();
            if scene.objects[pa.object].moves() {
                assert!(moved > 0.1);
            } else {
                assert_eq!(moved, 0.0);
            }
        }
    }

    /// Moving the moving objects of a placement to `t` gives `place(t)` to the bit (the
    /// renderer places the static objects once per frame).
    #[test]
    fn place_moving_is_place() {
        let key = |p: &Placed| {
            let w = p.world_to_local(&Vector3::new(0.3, -0.7, 1.1));
            [p.centre.x, p.centre.y, p.centre.z, p.radius, w.x, w.y, w.z].map(f64::to_bits)
        };
        for moving in [
            MovingObjects::default(),
            MovingObjects {
                count: 2,
                speed: 1.0,
                bodies: Some(Activity::Walking),
            },
        ] {
            let scene = Scene::new(4, Some(&moving));
            let mut placed = scene.place(0.0);
            for t in [0.25, 1.7, 13.0] {
                scene.place_moving(t, &mut placed);
                let fresh = scene.place(t);
                assert_eq!(placed.len(), fresh.len());
                for (a, b) in placed.iter().zip(&fresh) {
                    assert_eq!((a.object, key(a)), (b.object, key(b)), "t {t}");
                }
            }
        }
    }

    #[test]
    fn furniture_clearance_is_signed_and_agrees_with_the_scene() {
        // Inside the pillar, on the table top, in free space.
        assert!(furniture_clearance(&Vector3::new(-1.3, 0.3, 1.0)) < -0.1);
        assert!(furniture_clearance(&Vector3::new(0.0, 1.0, 0.75)).abs() < 1e-12);
        let q = Vector3::new(0.0, -0.5, 1.4);
        let c = furniture_clearance(&q);
        assert!(c > 0.3, "{c}");
        // Free space: never further from furniture than from the nearest surface at all.
        let scene = Scene::new(2, None);
        assert!(scene.surface_distance(&scene.place(0.0), &q) <= c + 1e-12);
    }
}
