//! The world a sequence is rendered in: a textured room, its furniture and the people in it,
//! built once per (specification, seed) and placed at any time for the ray-caster.
//!
//! Lowest first (each file uses only those above it in this list):
//! - [`shape`]: boxes and cylinders, and the geometry asked of them;
//! - [`texture`]: the procedural textures surfaces are painted with;
//! - [`people`]: articulated people who walk, stop, turn, sit and get up, and their chairs;
//! - [`layout`]: rooms and their furniture — the presets' fixed office (its size and
//!   furniture, which recorded paths are placed clear of) and layouts drawn from the seed;
//! - [`scene`]: the room, objects, textures and moving people together, placed at a time and
//!   intersected by rays.

pub mod layout;
pub mod people;
pub mod scene;
pub mod shape;
pub mod texture;
