//! The shapes the world is built of (boxes and vertical cylinders, each in its local frame:
//! centred at the origin, z up) and the geometry every stage asks of them: bounding sphere,
//! texture size, signed distance.

use nalgebra::Vector3;

/// The shape of an object, in its local frame (centred at the origin, z up).
#[derive(Clone, Copy, Debug)]
pub enum Shape {
    /// Axis-aligned box with the given half extents (metres).
    Cuboid {
        /// Half extents x, y, z.
        half: [f64; 3],
    },
    /// Vertical cylinder.
    Cylinder {
        /// Radius, metres.
        radius: f64,
        /// Half height, metres.
        half_height: f64,
    },
}

impl Shape {
    /// Radius of a sphere around the local origin containing the shape.
    pub fn bound(&self) -> f64 {
        match *self {
            Shape::Cuboid { half } => {
                (half[0] * half[0] + half[1] * half[1] + half[2] * half[2]).sqrt()
            }
            Shape::Cylinder {
                radius,
                half_height,
            } => (radius * radius + half_height * half_height).sqrt(),
        }
    }

    /// Metric size (width, height) of a texture that covers every face without stretching.
    pub fn texture_size(&self) -> (f64, f64) {
        match *self {
            Shape::Cuboid { half } => {
                let m = 2.0 * half[0].max(half[1]).max(half[2]);
                (m.max(0.3), m.max(0.3))
            }
            Shape::Cylinder {
                radius,
                half_height,
            } => (
                std::f64::consts::TAU * radius,
                (2.0 * half_height).max(2.0 * radius),
            ),
        }
    }

    /// Signed distance (metres) from a point `l` in the local frame to the shape: negative
    /// inside.
    pub fn signed_distance(&self, l: &Vector3<f64>) -> f64 {
        match *self {
            Shape::Cuboid { half } => {
                let d = Vector3::new(
                    l.x.abs() - half[0],
                    l.y.abs() - half[1],
                    l.z.abs() - half[2],
                );
                let outside = Vector3::new(d.x.max(0.0), d.y.max(0.0), d.z.max(0.0)).norm();
                outside + d.x.max(d.y).max(d.z).min(0.0)
            }
            Shape::Cylinder {
                radius,
                half_height,
            } => {
                let dr = (l.x * l.x + l.y * l.y).sqrt() - radius;
                let dz = l.z.abs() - half_height;
                let outside = (dr.max(0.0).powi(2) + dz.max(0.0).powi(2)).sqrt();
                outside + dr.max(dz).min(0.0)
            }
        }
    }
}
