//! The sensor: what the camera makes of the world at one instant.
//!
//! Lowest first (each file uses only those above it in this list, and the world):
//! - [`imaging`]: the colour camera — exposure (motion blur), rolling shutter, vignetting,
//!   auto-exposure, shot and read noise, and the grey levels they give;
//! - [`render`]: the parallel ray-caster (depth, incidence, ids, anti-aliased colour, lens
//!   distortion, colour exposed over time);
//! - [`depth`]: the depth-sensor model (axial, quantisation, lateral, holes, misregistration,
//!   lag, systematic distortion).

pub mod depth;
pub mod imaging;
pub mod render;
