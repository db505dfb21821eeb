//! Rooms and their furniture: the fixed office of the presets, and layouts drawn from the
//! sequence seed for the twins (an office of varying size with other furniture and other
//! things on the desk each seed, a Vicon-like motion-capture room, a machine hall).
//!
//! A seeded layout keeps its furniture off the camera's lines of sight ([`SightLine`]): a real
//! sequence is recorded where the camera can see what it was pointed at, so nothing may stand
//! within 0.4 m of the camera or of the first 1.2 m of its optical axis (further away, a
//! turning camera would leave no place for anything). The
//! desk of the office stays where the twins' paths look (table top at (0, 1, 0.75)); what lies
//! on it and what stands around it changes.
//!
//! The layout draws from its own `ChaCha8Rng` (seed ^ a salt), so the textures, which the
//! scene draws from another, are those of the fixed layout wherever the two share an object.
//!
//! An office may also have a [`Centrepiece`]: an object a twin's camera circles (fr1_plant's
//! potted plant, fr1_teddy's teddy bear), composed of boxes and cylinders and standing on the
//! floor in front of the desk ([`CENTREPIECE_AT`]); it is appended after the furniture and
//! draws nothing from the layout's generator, so a layout without one is unchanged.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::world::people::CHAIRS;
use crate::world::shape::Shape;
use crate::world::texture::Style;

/// Half extents of the fixed office along x and y, metres.
pub const ROOM_HALF: f64 = 2.5;
/// Height of the fixed office (ceiling), metres.
pub const ROOM_HEIGHT: f64 = 2.7;

/// The kind of room a sequence is rendered in ([`layout`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Room {
    /// The 5 x 5 x 2.7 m office around a desk of every preset (larger with a seeded layout).
    #[default]
    Office,
    /// A motion-capture room like EuRoC's Vicon room: about 8 x 8 x 4 m, its walls lined with
    /// grey padded mats, a grey carpet with marker strips, a play mat and a checkerboard.
    ViconRoom,
    /// An industrial hall like EuRoC's machine hall: about 20 x 14 x 9 m of concrete with
    /// machines, columns, shelves and crates.
    MachineHall,
}

/// The room and how its furniture is placed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneSpec {
    /// The room.
    pub room: Room,
    /// Furniture and clutter drawn from the sequence seed (room size, what stands where, what
    /// lies on the desk), kept off the camera's lines of sight. Off: the office's fixed
    /// furniture, or the other rooms' layout of seed 0.
    pub seeded_layout: bool,
    /// An object standing at [`CENTREPIECE_AT`] for the camera to circle (offices only), or
    /// none (default).
    pub centrepiece: Option<Centrepiece>,
}

/// An object a twin's camera circles at close range, composed of boxes and vertical cylinders
/// (the renderer's only shapes) and textured like the real thing's surfaces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Centrepiece {
    /// A potted plant about 1.1 m tall (fr1_plant): a pot, a stem and 14 leaves as thin
    /// horizontal boxes at several yaws and heights, spiralling up the stem.
    Plant,
    /// A teddy bear about 0.5 m tall sitting on a low stool (fr1_teddy): body, head, snout,
    /// ears, arms and legs.
    Teddy,
}

/// Where a [`Centrepiece`] stands: on the floor in the open part of the office, 1.3 m in front
/// of the desk's near edge (x, y, metres), over 1.1 m from the fixed office's other furniture,
/// so that a camera can circle it at about a metre.
pub const CENTREPIECE_AT: [f64; 2] = [0.2, -0.75];

/// Footprint radius kept free of other furniture round a centrepiece, metres.
pub const CENTREPIECE_RADIUS: f64 = 0.4;

impl Centrepiece {
    /// Its parts, standing at [`CENTREPIECE_AT`] on the floor.
    pub fn parts(&self) -> Vec<Furnishing> {
        let [x, y] = CENTREPIECE_AT;
        match self {
            Centrepiece::Plant => {
                let mut parts = vec![
                    // A terracotta-like pot, a rim of soil, a stem.
                    cylinder(x, y, 0.0, 0.17, 0.34, Style::Poster),
                    cylinder(x, y, 0.34, 0.19, 0.04, Style::Poster),
                    cylinder(x, y, 0.38, 0.02, 0.7, Style::Foliage),
                ];
                // Leaves spiralling up the stem at the golden angle, longer low down.
                for k in 0..14 {
                    let yaw = k as f64 * 2.39996;
                    let len = 0.17 - 0.006 * k as f64;
                    let (c, s) = (yaw.cos(), yaw.sin());
                    let r = 0.02 + len;
                    parts.push(cuboid(
                        [x + r * c, y + r * s, 0.5 + 0.042 * k as f64],
                        [len, 0.045 + 0.01 * (k % 3) as f64, 0.006],
                        yaw,
                        Style::Foliage,
                    ));
                }
                parts
            }
            Centrepiece::Teddy => {
                // Facing -y (towards where the twins' paths start); local x forward, y left.
                let facing = -std::f64::consts::FRAC_PI_2;
                let (c, s) = (facing.cos(), facing.sin());
                let at = |fwd: f64, left: f64, z: f64| {
                    [x + c * fwd - s * left, y + s * fwd + c * left, z]
                };
                let fur = Style::Fur;
                let seat = 0.4;
                let mut parts = vec![
                    cuboid(
                        [x, y, seat / 2.0],
                        [0.22, 0.22, seat / 2.0],
                        0.3,
                        Style::Poster,
                    ),
                    // Body and head.
                    cylinder(x, y, seat, 0.13, 0.28, fur),
                    cylinder(x, y, seat + 0.28, 0.1, 0.17, fur),
                ];
                let part = |fwd: f64, left: f64, z: f64, half: [f64; 3]| {
                    cuboid(at(fwd, left, z), half, facing, fur)
                };
                parts.extend([
                    // Snout.
                    part(0.11, 0.0, seat + 0.34, [0.035, 0.045, 0.035]),
                    // Arms.
                    part(0.03, 0.16, seat + 0.15, [0.045, 0.04, 0.1]),
                    part(0.03, -0.16, seat + 0.15, [0.045, 0.04, 0.1]),
                    // Legs, stretched forward.
                    part(0.15, 0.07, seat + 0.045, [0.1, 0.05, 0.045]),
                    part(0.15, -0.07, seat + 0.045, [0.1, 0.05, 0.045]),
                ]);
                for left in [0.075, -0.075] {
                    let [ex, ey, _] = at(0.0, left, 0.0);
                    parts.push(cylinder(ex, ey, seat + 0.45, 0.035, 0.035, fur));
                }
                parts
            }
        }
    }
}

/// The room's box: x in `[-half[0], half[0]]`, y in `[-half[1], half[1]]`, z in `[0, height]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoomBox {
    /// Half extents along x and y, metres.
    pub half: [f64; 2],
    /// Height of the ceiling, metres.
    pub height: f64,
}

/// One static object of a layout and the texture style it is painted in.
#[derive(Clone, Copy, Debug)]
pub struct Furnishing {
    /// Geometry in the local frame.
    pub shape: Shape,
    /// Centre in the world, metres.
    pub centre: [f64; 3],
    /// Rotation about the vertical, radians.
    pub yaw: f64,
    /// How its texture is drawn.
    pub style: Style,
}

/// A room with its faces' styles, furniture and light.
#[derive(Clone, Debug)]
pub struct Layout {
    /// The room's box.
    pub room: RoomBox,
    /// Styles of the six faces: floor, ceiling, -x, +x, -y, +y walls.
    pub faces: [Style; 6],
    /// Texel size of the floor and walls, metres (the ceiling's is at least 1 cm).
    pub face_texel_m: f64,
    /// The static objects, desk first in the office.
    pub objects: Vec<Furnishing>,
    /// The point light, world metres.
    pub light: Vector3<f64>,
}

/// A stretch of the camera's view that furniture must stay clear of: from the camera centre
/// (`eye`) to `end`, [`SIGHT_CLEAR_M`] along the optical axis (or where it meets the floor).
#[derive(Clone, Copy, Debug)]
pub struct SightLine {
    /// Camera centre, world metres.
    pub eye: Vector3<f64>,
    /// End of the kept-clear stretch, world metres.
    pub end: Vector3<f64>,
}

/// Length of the optical axis kept clear of furniture, metres.
pub const SIGHT_CLEAR_M: f64 = 1.2;
/// Horizontal gap kept between furniture and a line of sight, metres (on top of the object's
/// footprint radius).
const SIGHT_MARGIN_M: f64 = 0.4;

impl SightLine {
    /// The kept-clear stretch of a camera at `eye` looking along unit `axis`.
    pub fn new(eye: Vector3<f64>, axis: Vector3<f64>) -> SightLine {
        let mut len = SIGHT_CLEAR_M;
        if axis.z < -1e-9 {
            len = len.min(eye.z / -axis.z);
        }
        SightLine {
            eye,
            end: eye + axis * len,
        }
    }
}

/// The layout of `spec` for sequence `seed`. `sight` are the camera's lines of sight (used by
/// seeded layouts only); `people` says whether the scene has the people's chairs (kept clear).
/// An office's centrepiece (see [`SceneSpec::centrepiece`]) comes last among its objects.
pub fn layout(spec: &SceneSpec, seed: u64, sight: &[SightLine], people: bool) -> Layout {
    let layout_seed = if spec.seeded_layout { seed } else { 0 };
    let mut rng = ChaCha8Rng::seed_from_u64(layout_seed ^ 0x1A40_u64.rotate_left(48) ^ 0x0FF1CE);
    let centrepiece = spec.centrepiece.filter(|_| spec.room == Room::Office);
    let mut l = match (spec.room, spec.seeded_layout) {
        (Room::Office, false) => fixed_office(people),
        (Room::Office, true) => seeded_office(&mut rng, sight, people, centrepiece.is_some()),
        (Room::ViconRoom, _) => vicon_room(&mut rng, sight),
        (Room::MachineHall, _) => machine_hall(&mut rng, sight),
    };
    if let Some(c) = centrepiece {
        l.objects.extend(c.parts());
    }
    l
}

fn cuboid(centre: [f64; 3], half: [f64; 3], yaw: f64, style: Style) -> Furnishing {
    Furnishing {
        shape: Shape::Cuboid { half },
        centre,
        yaw,
        style,
    }
}

fn cylinder(x: f64, y: f64, z0: f64, radius: f64, height: f64, style: Style) -> Furnishing {
    Furnishing {
        shape: Shape::Cylinder {
            radius,
            half_height: height / 2.0,
        },
        centre: [x, y, z0 + height / 2.0],
        yaw: 0.0,
        style,
    }
}

/// Height of the office's table top, metres.
const TABLE_TOP: f64 = 0.75;
/// Index in the fixed office of the first object standing on the floor (the ones before are
/// the table and what stands on it).
const FIRST_FLOOR_OBJECT: usize = 11;

/// The table top and its four legs.
fn desk() -> Vec<Furnishing> {
    let leg = |x: f64, y: f64| cuboid([x, y, 0.35], [0.025, 0.025, 0.35], 0.0, Style::Poster);
    vec![
        cuboid(
            [0.0, 1.0, TABLE_TOP - 0.025],
            [0.8, 0.45, 0.025],
            0.0,
            Style::Desk,
        ),
        leg(-0.75, 0.6),
        leg(0.75, 0.6),
        leg(-0.75, 1.4),
        leg(0.75, 1.4),
    ]
}

/// The office of every preset: a table with legs and things on it, a cabinet, boxes, a pillar,
/// a shelf, a bin; the same for every seed (only textures vary). With people, the things on the
/// floor are plain office cabinets.
fn fixed_office(people: bool) -> Layout {
    let t = TABLE_TOP;
    let p = Style::Poster;
    let mut objects = desk();
    objects.extend([
        // On the table: boxes, a book, a monitor panel, a bottle and a pot.
        cuboid([-0.45, 0.9, t + 0.10], [0.12, 0.09, 0.10], 0.3, p),
        cuboid([0.42, 1.15, t + 0.17], [0.15, 0.12, 0.17], -0.4, p),
        cuboid([0.05, 0.75, t + 0.025], [0.14, 0.10, 0.025], 0.15, p),
        cuboid([-0.15, 1.36, t + 0.25], [0.3, 0.02, 0.2], 0.0, p),
        cylinder(-0.12, 1.1, t, 0.045, 0.24, p),
        cylinder(0.62, 0.78, t, 0.07, 0.18, p),
        // On the floor: cabinet, boxes, a pillar, a shelf, a bin.
        cuboid([-1.6, 1.9, 0.6], [0.45, 0.3, 0.6], 0.0, p),
        cuboid([1.45, 1.55, 0.3], [0.3, 0.3, 0.3], 0.5, p),
        cuboid([1.45, 1.55, 0.75], [0.2, 0.18, 0.15], 0.2, p),
        cylinder(-1.3, 0.3, 0.0, 0.15, 1.8, p),
        cuboid([2.0, -1.5, 0.4], [0.35, 0.25, 0.4], 0.2, p),
        cuboid([-2.0, -1.2, 0.5], [0.3, 0.4, 0.5], 0.0, p),
        cylinder(0.8, -2.0, 0.0, 0.2, 0.6, p),
        cuboid([-0.5, -2.25, 0.8], [0.6, 0.2, 0.8], 0.0, p),
        cuboid([2.2, 0.4, 1.0], [0.25, 0.6, 1.0], 0.0, p),
    ]);
    if people {
        for o in &mut objects[FIRST_FLOOR_OBJECT..] {
            o.style = Style::OfficeWall;
        }
    }
    let faces = if people {
        let (f, w) = (Style::OfficeFloor, Style::OfficeWall);
        [f, f, w, w, w, w]
    } else {
        let (c, p) = (Style::Carpet, Style::Poster);
        [c, p, p, p, p, p]
    };
    Layout {
        room: RoomBox {
            half: [ROOM_HALF, ROOM_HALF],
            height: ROOM_HEIGHT,
        },
        faces,
        face_texel_m: 0.004,
        objects,
        light: Vector3::new(0.3, 0.0, 2.6),
    }
}

/// The fixed office's furniture (shape, centre, yaw): what recorded paths are placed clear of.
pub fn fixed_office_shapes() -> Vec<(Shape, [f64; 3], f64)> {
    fixed_office(false)
        .objects
        .into_iter()
        .map(|o| (o.shape, o.centre, o.yaw))
        .collect()
}

/// Signed distance (metres) from world point `q` to the nearest piece of the room's fixed
/// furniture (negative inside one; walls, floor, ceiling and moving objects not counted): how
/// close a camera placed at `q` would be to an object, used to place recorded paths.
pub fn furniture_clearance(q: &Vector3<f64>) -> f64 {
    static LAYOUT: std::sync::OnceLock<Vec<(Shape, [f64; 3], f64)>> = std::sync::OnceLock::new();
    LAYOUT
        .get_or_init(fixed_office_shapes)
        .iter()
        .map(|(shape, c, yaw)| {
            let r = q - Vector3::new(c[0], c[1], c[2]);
            let (co, si) = (yaw.cos(), yaw.sin());
            let l = Vector3::new(co * r.x + si * r.y, -si * r.x + co * r.y, r.z);
            shape.signed_distance(&l)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Radius of the footprint of a shape about its centre, metres.
fn footprint(shape: &Shape) -> f64 {
    match *shape {
        Shape::Cuboid { half } => half[0].hypot(half[1]),
        Shape::Cylinder { radius, .. } => radius,
    }
}

/// Top of a shape centred at height `z`, metres.
fn top(shape: &Shape, z: f64) -> f64 {
    match *shape {
        Shape::Cuboid { half } => z + half[2],
        Shape::Cylinder { half_height, .. } => z + half_height,
    }
}

/// Where furniture may not go: the lines of sight and what already stands.
struct Placement<'a> {
    sight: &'a [SightLine],
    /// Footprint discs taken (x, y, radius).
    taken: Vec<(f64, f64, f64)>,
    room: RoomBox,
}

impl Placement<'_> {
    /// Whether a shape centred at `c` fits: inside the room, off the taken discs, off the lines
    /// of sight below its top.
    fn fits(&self, shape: &Shape, c: [f64; 3]) -> bool {
        let r = footprint(shape);
        if c[0].abs() + r > self.room.half[0] || c[1].abs() + r > self.room.half[1] {
            return false;
        }
        if self
            .taken
            .iter()
            .any(|&(x, y, rt)| (c[0] - x).hypot(c[1] - y) < r + rt + 0.1)
        {
            return false;
        }
        let top = top(shape, c[2]);
        let clear = r + SIGHT_MARGIN_M;
        !self.sight.iter().any(|s| {
            let d = s.end - s.eye;
            let steps = ((d.norm() / 0.2).ceil() as usize).max(1);
            (0..=steps).any(|k| {
                let p = s.eye + d * (k as f64 / steps as f64);
                p.z < top + 0.3 && (p.x - c[0]).hypot(p.y - c[1]) < clear
            })
        })
    }

    /// Tries up to 60 positions from `draw` and keeps the first that fits.
    fn place(
        &mut self,
        rng: &mut ChaCha8Rng,
        out: &mut Vec<Furnishing>,
        mut draw: impl FnMut(&mut ChaCha8Rng) -> Furnishing,
    ) -> bool {
        for _ in 0..60 {
            let f = draw(rng);
            if self.fits(&f.shape, f.centre) {
                self.taken
                    .push((f.centre[0], f.centre[1], footprint(&f.shape)));
                out.push(f);
                return true;
            }
        }
        false
    }
}

/// A position against a random wall for an object of half depth `depth` (its local x across
/// the wall), with the yaw that turns it to face the room.
fn against_wall(rng: &mut ChaCha8Rng, room: &RoomBox, depth: f64, gap: f64) -> (f64, f64, f64) {
    let [hx, hy] = room.half;
    let d = depth + gap;
    match rng.random_range(0..4) {
        0 => (-hx + d, rng.random_range(-hy + 0.5..hy - 0.5), 0.0),
        1 => (hx - d, rng.random_range(-hy + 0.5..hy - 0.5), 0.0),
        2 => (
            rng.random_range(-hx + 0.5..hx - 0.5),
            -hy + d,
            std::f64::consts::FRAC_PI_2,
        ),
        _ => (
            rng.random_range(-hx + 0.5..hx - 0.5),
            hy - d,
            std::f64::consts::FRAC_PI_2,
        ),
    }
}

/// Ranges of the half extents (x, y, z) of the boxes on a desk: a box, a book, a monitor.
const DESK_BOXES: [[(f64, f64); 3]; 3] = [
    [(0.06, 0.16), (0.05, 0.13), (0.04, 0.18)],
    [(0.08, 0.15), (0.06, 0.11), (0.01, 0.03)],
    [(0.18, 0.3), (0.02, 0.02), (0.13, 0.22)],
];

/// A value uniform in `[r.0, r.1)`, or `r.0` without a draw when the range is a point.
fn draw(rng: &mut ChaCha8Rng, r: (f64, f64)) -> f64 {
    if r.0 == r.1 {
        r.0
    } else {
        rng.random_range(r.0..r.1)
    }
}

/// An office of 5-7 x 5-7 m: the desk where the twins look, 5-9 things on it, 6-11 pieces of
/// furniture around (most against the walls), none within [`CENTREPIECE_RADIUS`] of
/// [`CENTREPIECE_AT`] when the office has a centrepiece.
fn seeded_office(
    rng: &mut ChaCha8Rng,
    sight: &[SightLine],
    people: bool,
    centrepiece: bool,
) -> Layout {
    let room = RoomBox {
        half: [rng.random_range(2.5..3.5), rng.random_range(2.5..3.5)],
        height: rng.random_range(2.6..3.0),
    };
    let mut objects = desk();
    let p = Style::Poster;
    // On the desk: non-overlapping footprints within the top.
    let mut on_desk: Vec<(f64, f64, f64)> = Vec::new();
    let n = rng.random_range(5..=9);
    for _ in 0..n {
        for _ in 0..40 {
            let yaw = rng.random_range(-0.6..0.6);
            let (shape, z_half) = match rng.random_range(0..5) {
                k @ 0..=2 => {
                    let h = DESK_BOXES[k].map(|r| draw(rng, r));
                    (Shape::Cuboid { half: h }, h[2])
                }
                3 => {
                    let hh = rng.random_range(0.07..0.15);
                    (
                        Shape::Cylinder {
                            radius: rng.random_range(0.03..0.05),
                            half_height: hh,
                        },
                        hh,
                    )
                }
                _ => {
                    let hh = rng.random_range(0.04..0.08);
                    (
                        Shape::Cylinder {
                            radius: rng.random_range(0.04..0.07),
                            half_height: hh,
                        },
                        hh,
                    )
                }
            };
            let r = footprint(&shape);
            if r > 0.4 {
                continue;
            }
            let x = rng.random_range(-0.78 + r..0.78 - r);
            let y = rng.random_range(0.57 + r..1.43 - r);
            if on_desk
                .iter()
                .any(|&(ox, oy, or)| (x - ox).hypot(y - oy) < r + or + 0.02)
            {
                continue;
            }
            on_desk.push((x, y, r));
            objects.push(Furnishing {
                shape,
                centre: [x, y, TABLE_TOP + z_half],
                yaw,
                style: p,
            });
            break;
        }
    }
    let first_floor = objects.len();
    let mut place = Placement {
        sight,
        // The desk with room to pull a chair out.
        taken: vec![(0.0, 1.0, 0.92 + 0.2)],
        room,
    };
    if people {
        for c in CHAIRS.iter() {
            place.taken.push((c.at[0], c.at[1], 0.8));
        }
    }
    if centrepiece {
        let [x, y] = CENTREPIECE_AT;
        place.taken.push((x, y, CENTREPIECE_RADIUS));
    }
    let n = rng.random_range(6..=11);
    for _ in 0..n {
        place.place(rng, &mut objects, |rng| {
            let kind = rng.random_range(0..6);
            let half = match kind {
                // Cabinet, shelf, box, low chest.
                0 => [
                    0.25,
                    rng.random_range(0.3..0.5),
                    rng.random_range(0.4..0.75),
                ],
                1 => [0.2, rng.random_range(0.4..0.7), rng.random_range(0.8..1.0)],
                2 => [rng.random_range(0.15..0.35); 3],
                3 => [0.3, rng.random_range(0.4..0.8), rng.random_range(0.2..0.35)],
                // Pillar, bin.
                4 => [rng.random_range(0.1..0.2), 0.0, rng.random_range(0.8..1.1)],
                _ => [
                    rng.random_range(0.12..0.22),
                    0.0,
                    rng.random_range(0.2..0.35),
                ],
            };
            if kind >= 4 {
                let (x, y, _) = if rng.random_bool(0.5) {
                    against_wall(rng, &room, half[0], 0.05)
                } else {
                    free_spot(rng, &room, 0.3)
                };
                return cylinder(x, y, 0.0, half[0], 2.0 * half[2], p);
            }
            let (x, y, yaw) = if rng.random_bool(0.75) {
                let gap = rng.random_range(0.0..0.1);
                let (x, y, yaw) = against_wall(rng, &room, half[0], gap);
                (x, y, yaw + rng.random_range(-0.08..0.08))
            } else {
                free_spot(rng, &room, 0.3)
            };
            cuboid([x, y, half[2]], half, yaw, p)
        });
    }
    let (c, pf) = if people {
        (Style::OfficeFloor, Style::OfficeWall)
    } else {
        (Style::Carpet, Style::Poster)
    };
    if people {
        for o in &mut objects[first_floor..] {
            o.style = Style::OfficeWall;
        }
    }
    Layout {
        room,
        faces: [c, if people { c } else { pf }, pf, pf, pf, pf],
        face_texel_m: 0.004,
        objects,
        light: Vector3::new(
            rng.random_range(-0.5..0.5),
            rng.random_range(-0.5..0.5),
            room.height - 0.1,
        ),
    }
}

/// A uniform spot in the room at least `margin` from the walls, with a random yaw.
fn free_spot(rng: &mut ChaCha8Rng, room: &RoomBox, margin: f64) -> (f64, f64, f64) {
    let [hx, hy] = room.half;
    (
        rng.random_range(-hx + margin..hx - margin),
        rng.random_range(-hy + margin..hy - margin),
        rng.random_range(0.0..std::f64::consts::PI),
    )
}

/// A motion-capture room like EuRoC's (V1_01's frames): about 8 x 8 x 4 m, curtains above
/// grey padded mats standing side by side along every wall, a grey carpet with black marker
/// strips, a printed play mat, a checkerboard against the mats, a few mats and foam blocks
/// standing in the room.
fn vicon_room(rng: &mut ChaCha8Rng, sight: &[SightLine]) -> Layout {
    let room = RoomBox {
        half: [rng.random_range(3.8..4.3), rng.random_range(3.8..4.3)],
        height: rng.random_range(3.6..4.2),
    };
    let mut objects = Vec::new();
    // Mats along the walls: local x across the wall (thickness), y along it.
    for wall in 0..4 {
        let along_half = if wall < 2 { room.half[1] } else { room.half[0] };
        let mut s = -along_half + rng.random_range(0.0..0.3);
        while s < along_half - 0.6 {
            let w = rng.random_range(1.0..1.6f64).min(along_half - s);
            let thick = rng.random_range(0.06..0.1);
            let tall = rng.random_range(0.9..1.1);
            if !rng.random_bool(0.12) {
                let gap = thick + 0.05 + rng.random_range(0.0..0.1);
                let mid = s + w / 2.0;
                let (x, y, yaw) = match wall {
                    0 => (-room.half[0] + gap, mid, 0.0),
                    1 => (room.half[0] - gap, mid, 0.0),
                    2 => (mid, -room.half[1] + gap, std::f64::consts::FRAC_PI_2),
                    _ => (mid, room.half[1] - gap, std::f64::consts::FRAC_PI_2),
                };
                objects.push(cuboid(
                    [x, y, tall],
                    [thick, w / 2.0 - 0.01, tall],
                    yaw + rng.random_range(-0.06..0.06),
                    Style::Mat,
                ));
            }
            s += w + rng.random_range(0.0..0.08);
        }
    }
    let mut place = Placement {
        sight,
        taken: Vec::new(),
        room: RoomBox {
            half: [room.half[0] - 0.35, room.half[1] - 0.35],
            ..room
        },
    };
    // A checkerboard standing against the mats.
    place.place(rng, &mut objects, |rng| {
        let (x, y, yaw) = against_wall(rng, &room, 0.01, 0.25);
        cuboid([x, y, 0.26], [0.01, 0.2, 0.26], yaw, Style::Checker)
    });
    // Mats and foam blocks standing in the room.
    for _ in 0..rng.random_range(1..=3) {
        place.place(rng, &mut objects, |rng| {
            let gap = rng.random_range(0.4..1.0);
            let (x, y, yaw) = against_wall(rng, &room, 0.08, gap);
            let half = [0.08, rng.random_range(0.5..0.9), rng.random_range(0.6..1.0)];
            cuboid(
                [x, y, half[2]],
                half,
                yaw + rng.random_range(-0.3..0.3),
                Style::Mat,
            )
        });
    }
    for _ in 0..rng.random_range(2..=4) {
        place.place(rng, &mut objects, |rng| {
            let (x, y, yaw) = free_spot(rng, &room, 0.8);
            let half = [
                rng.random_range(0.2..0.5),
                rng.random_range(0.2..0.5),
                rng.random_range(0.15..0.45),
            ];
            let style = if rng.random_bool(0.5) {
                Style::Mat
            } else {
                Style::Poster
            };
            cuboid([x, y, half[2]], half, yaw, style)
        });
    }
    // Flat things on the carpet (below every line of sight): strips and play mats.
    for k in 0..rng.random_range(4..=7) {
        let (x, y, yaw) = free_spot(rng, &room, 1.2);
        let (half, style) = if k < 2 {
            (
                [
                    rng.random_range(0.5..0.7),
                    rng.random_range(0.8..1.0),
                    0.004,
                ],
                Style::Poster,
            )
        } else {
            (
                [0.07, rng.random_range(0.6..1.2), 0.003],
                Style::MarkerStrip,
            )
        };
        objects.push(cuboid([x, y, half[2]], half, yaw, style));
    }
    Layout {
        room,
        faces: [
            Style::OfficeFloor,
            Style::Curtain,
            Style::Curtain,
            Style::Curtain,
            Style::Curtain,
            Style::Curtain,
        ],
        face_texel_m: 0.005,
        objects,
        light: Vector3::new(0.0, 0.0, room.height - 0.2),
    }
}

/// An industrial hall like EuRoC's machine hall: about 20 x 14 x 9 m of concrete, columns
/// along the long walls, shelves against the walls, machines, tanks and crates in the hall.
fn machine_hall(rng: &mut ChaCha8Rng, sight: &[SightLine]) -> Layout {
    let room = RoomBox {
        half: [rng.random_range(9.0..11.0), rng.random_range(6.5..8.0)],
        height: rng.random_range(8.0..10.0),
    };
    let mut objects = Vec::new();
    // Columns along the long walls.
    let step = rng.random_range(4.0..6.0);
    let mut x = -room.half[0] + 2.0;
    while x < room.half[0] - 1.0 {
        for side in [-1.0, 1.0] {
            let y = side * (room.half[1] - 0.5);
            objects.push(cuboid(
                [x, y, room.height / 2.0],
                [0.25, 0.25, room.height / 2.0],
                0.0,
                Style::Concrete,
            ));
        }
        x += step;
    }
    let mut place = Placement {
        sight,
        taken: objects
            .iter()
            .map(|o| (o.centre[0], o.centre[1], 0.36))
            .collect(),
        room,
    };
    // Shelves against the walls.
    for _ in 0..rng.random_range(3..=6) {
        place.place(rng, &mut objects, |rng| {
            let half = [0.4, rng.random_range(1.0..2.5), rng.random_range(1.0..2.0)];
            let (x, y, yaw) = against_wall(rng, &room, half[0], 0.8);
            cuboid([x, y, half[2]], half, yaw, Style::Poster)
        });
    }
    // Machines (some with a smaller part on top), tanks and crates.
    for _ in 0..rng.random_range(8..=14) {
        let placed = place.place(rng, &mut objects, |rng| {
            let (x, y, yaw) = free_spot(rng, &room, 1.5);
            let half = [
                rng.random_range(0.5..2.0),
                rng.random_range(0.5..1.5),
                rng.random_range(0.5..2.0),
            ];
            cuboid([x, y, half[2]], half, yaw, Style::Machine)
        });
        if placed && rng.random_bool(0.5) {
            let base = *objects.last().expect("just placed");
            if let Shape::Cuboid { half } = base.shape {
                let h = [half[0] * 0.5, half[1] * 0.6, rng.random_range(0.3..1.0)];
                objects.push(cuboid(
                    [base.centre[0], base.centre[1], 2.0 * half[2] + h[2]],
                    h,
                    base.yaw,
                    Style::Machine,
                ));
            }
        }
    }
    for _ in 0..rng.random_range(3..=5) {
        place.place(rng, &mut objects, |rng| {
            let (x, y, _) = free_spot(rng, &room, 1.5);
            cylinder(
                x,
                y,
                0.0,
                rng.random_range(0.3..0.8),
                rng.random_range(1.0..4.0),
                Style::Machine,
            )
        });
    }
    for _ in 0..rng.random_range(6..=10) {
        place.place(rng, &mut objects, |rng| {
            let (x, y, yaw) = free_spot(rng, &room, 0.8);
            let half = [rng.random_range(0.2..0.5); 3];
            cuboid([x, y, half[2]], half, yaw, Style::Poster)
        });
    }
    Layout {
        room,
        faces: [Style::Concrete; 6],
        face_texel_m: 0.01,
        objects,
        light: Vector3::new(0.0, 0.0, room.height - 0.5),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seeded(room: Room) -> SceneSpec {
        SceneSpec {
            room,
            seeded_layout: true,
            centrepiece: None,
        }
    }

    /// Standing on the table top (bottom at its height, centre above it).
    fn on_the_desk(o: &Furnishing) -> bool {
        let bottom = 2.0 * o.centre[2] - top(&o.shape, o.centre[2]);
        (bottom - TABLE_TOP).abs() < 1e-9
            && o.centre[0].abs() < 0.8
            && (o.centre[1] - 1.0).abs() < 0.45
    }

    /// Horizontal distance from `o`'s axis to the part of a line of sight less than 0.3 m above
    /// its top (where it could hide what the camera looks at).
    fn distance_below_sight(o: &Furnishing, s: &SightLine) -> f64 {
        let top = top(&o.shape, o.centre[2]);
        (0..=200)
            .map(|k| s.eye + (s.end - s.eye) * (k as f64 / 200.0))
            .filter(|p| p.z < top + 0.3)
            .map(|p| (p.x - o.centre[0]).hypot(p.y - o.centre[1]))
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn seeds_give_other_layouts_and_the_same_seed_the_same() {
        for room in [Room::Office, Room::ViconRoom, Room::MachineHall] {
            let a = layout(&seeded(room), 1, &[], false);
            let b = layout(&seeded(room), 2, &[], false);
            let a2 = layout(&seeded(room), 1, &[], false);
            assert_ne!(a.room, b.room, "{room:?}");
            assert_eq!(a.room, a2.room);
            assert_eq!(format!("{:?}", a.objects), format!("{:?}", a2.objects));
            assert_ne!(format!("{:?}", a.objects), format!("{:?}", b.objects));
            // Off: seed-independent.
            let spec = SceneSpec {
                room,
                seeded_layout: false,
                centrepiece: None,
            };
            assert_eq!(
                format!("{:?}", layout(&spec, 1, &[], false).objects),
                format!("{:?}", layout(&spec, 2, &[], false).objects)
            );
        }
    }

    #[test]
    fn rooms_have_their_sizes() {
        let office = layout(&SceneSpec::default(), 5, &[], false);
        assert_eq!(office.room.half, [ROOM_HALF; 2]);
        for seed in 0..20 {
            let o = layout(&seeded(Room::Office), seed, &[], false).room;
            assert!(o.half.iter().all(|h| (2.5..3.5).contains(h)), "{o:?}");
            let v = layout(&seeded(Room::ViconRoom), seed, &[], false).room;
            assert!(v.half.iter().all(|h| (3.8..4.3).contains(h)) && v.height > 3.5);
            let m = layout(&seeded(Room::MachineHall), seed, &[], false).room;
            assert!(
                m.half[0] >= 9.0 && m.half[1] >= 6.5 && m.height >= 8.0,
                "{m:?}"
            );
        }
    }

    #[test]
    fn furniture_stays_in_the_room_and_off_the_lines_of_sight() {
        // A camera crossing the room looking along +y, slightly down.
        let sight: Vec<SightLine> = (0..20)
            .map(|k| {
                let eye = Vector3::new(-1.5 + 0.15 * k as f64, -1.0, 1.4);
                SightLine::new(eye, Vector3::new(0.0, 0.95, -0.3).normalize())
            })
            .collect();
        for room in [Room::Office, Room::ViconRoom, Room::MachineHall] {
            for seed in 0..10 {
                let l = layout(&seeded(room), seed, &sight, false);
                let first_free = if room == Room::Office { 5 } else { 0 };
                let mut floor_things = 0;
                for o in &l.objects[first_free..] {
                    let r = footprint(&o.shape);
                    let (c, s) = (o.yaw.cos(), o.yaw.sin());
                    let corners: Vec<(f64, f64)> = match o.shape {
                        Shape::Cuboid { half } => {
                            [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)]
                                .iter()
                                .map(|(a, b)| (a * half[0], b * half[1]))
                                .map(|(x, y)| {
                                    (o.centre[0] + c * x - s * y, o.centre[1] + s * x + c * y)
                                })
                                .collect()
                        }
                        Shape::Cylinder { radius, .. } => vec![
                            (o.centre[0] - radius, o.centre[1] - radius),
                            (o.centre[0] + radius, o.centre[1] + radius),
                        ],
                    };
                    assert!(
                        corners.iter().all(|(x, y)| x.abs() <= l.room.half[0] + 1e-9
                            && y.abs() <= l.room.half[1] + 1e-9),
                        "{room:?} {seed}: {o:?} outside {:?}",
                        l.room
                    );
                    // On the desk or flat on the floor: below the lines of sight.
                    let on_desk = room == Room::Office && on_the_desk(o);
                    if on_desk || top(&o.shape, o.centre[2]) < 0.05 {
                        continue;
                    }
                    floor_things += 1;
                    for s in &sight {
                        assert!(
                            distance_below_sight(o, s) >= r + SIGHT_MARGIN_M - 0.11,
                            "{room:?} seed {seed}: {o:?} stands in a line of sight"
                        );
                    }
                }
                assert!(floor_things >= 3, "{room:?} {seed}: {floor_things}");
            }
        }
    }

    #[test]
    fn a_centrepiece_stands_on_the_floor_with_room_round_it() {
        for piece in [Centrepiece::Plant, Centrepiece::Teddy] {
            let parts = piece.parts();
            let [x, y] = CENTREPIECE_AT;
            let (mut bottom, mut height) = (f64::INFINITY, 0.0f64);
            for p in &parts {
                let t = top(&p.shape, p.centre[2]);
                bottom = bottom.min(2.0 * p.centre[2] - t);
                height = height.max(t);
                let d = (p.centre[0] - x).hypot(p.centre[1] - y) + footprint(&p.shape);
                assert!(
                    d <= CENTREPIECE_RADIUS,
                    "{piece:?}: {p:?} reaches {d} m out"
                );
            }
            assert!(bottom.abs() < 1e-9, "{piece:?} floats at {bottom}");
            assert!((0.8..1.2).contains(&height), "{piece:?}: {height} m tall");
            for seed in 0..10 {
                let spec = SceneSpec {
                    centrepiece: Some(piece),
                    ..seeded(Room::Office)
                };
                let l = layout(&spec, seed, &[], false);
                let plain = layout(&seeded(Room::Office), seed, &[], false);
                // Appended last; the furniture before it keeps its distance.
                let n = l.objects.len() - parts.len();
                assert_eq!(format!("{:?}", &l.objects[n..]), format!("{parts:?}"));
                for o in &l.objects[5..n] {
                    if on_the_desk(o) {
                        continue;
                    }
                    let d = (o.centre[0] - x).hypot(o.centre[1] - y);
                    assert!(d >= CENTREPIECE_RADIUS + footprint(&o.shape), "{o:?}");
                }
                // Other rooms and offices without one are unchanged by the option.
                assert_eq!(l.room, plain.room);
                let hall = SceneSpec {
                    centrepiece: Some(piece),
                    ..seeded(Room::MachineHall)
                };
                assert_eq!(
                    format!("{:?}", layout(&hall, seed, &[], false).objects),
                    format!(
                        "{:?}",
                        layout(&seeded(Room::MachineHall), seed, &[], false).objects
                    )
                );
            }
        }
    }

    #[test]
    fn things_on_the_desk_lie_on_its_top_without_overlapping() {
        for seed in 0..20 {
            let l = layout(&seeded(Room::Office), seed, &[], false);
            let on: Vec<&Furnishing> = l.objects[5..].iter().filter(|o| on_the_desk(o)).collect();
            assert!((5..=9).contains(&on.len()), "{}", on.len());
            for (i, a) in on.iter().enumerate() {
                let r = footprint(&a.shape);
                assert!(a.centre[0].abs() + r <= 0.8 && (a.centre[1] - 1.0).abs() + r <= 0.45);
                for b in &on[i + 1..] {
                    let d = (a.centre[0] - b.centre[0]).hypot(a.centre[1] - b.centre[1]);
                    assert!(d >= r + footprint(&b.shape), "{a:?} overlaps {b:?}");
                }
            }
        }
    }
}
