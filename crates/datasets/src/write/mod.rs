//! The one writer of TUM RGB-D and EuRoC ASL folders, beside the readers it must round-trip
//! with: every folder noisefree writes (`noisefree synth`, `noisefree perturb`, the sequences
//! given to external SLAM programs) goes through here, with one staging-and-rename.
//!
//! - [`files`]: the staging folder, text files, PNG images and 16-bit depth;
//! - [`tum`] and [`euroc`]: each layout's lists, calibration and ground-truth files;
//! - [`synthetic`]: a `synth` generator's frames as a folder ([`write_synthetic`]);
//! - [`sequence`]: any [`crate::Sequence`] as a folder ([`write_sequence`]).

pub mod euroc;
pub mod files;
pub mod sequence;
pub mod synthetic;
pub mod tum;

pub use sequence::{write_sequence, DEFAULT_DEPTH_UNITS};
pub use synthetic::write_synthetic;

/// How stamps and poses are printed in the lists a folder holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Digits {
    /// As the datasets' own files look: TUM stamps with 6 decimals, poses with 9, the
    /// quaternion's sign chosen so qw >= 0, a rectified pair's T_BS with 12 decimals. What
    /// `noisefree synth` writes: the sequences imitate the real ones.
    Dataset,
    /// Every digit needed to read back the same `f64` (the shortest round trip), the values as
    /// they are: a reader gets exactly the bits that were written. What an exported copy of a
    /// sequence needs, so that noisefree on the copy runs on what it ran on before.
    Exact,
}

impl Digits {
    /// A pose value (metres, or a quaternion coordinate) as these digits print it.
    fn value(self, x: f64) -> String {
        match self {
            Digits::Dataset => format!("{x:.9}"),
            Digits::Exact => format!("{x}"),
        }
    }

    /// The translation (x, y, z) and the quaternion (x, y, z, w) of `pose` as a ground-truth
    /// line prints them: with [`Digits::Dataset`] the quaternion's sign chosen so qw >= 0 (the
    /// datasets' convention), with [`Digits::Exact`] as it is.
    fn pose_values(self, pose: &nalgebra::Isometry3<f64>) -> ([String; 3], [String; 4]) {
        let v = pose.translation.vector;
        let mut q = *pose.rotation.quaternion();
        if self == Digits::Dataset && q.w < 0.0 {
            q = -q;
        }
        (
            [v.x, v.y, v.z].map(|x| self.value(x)),
            [q.i, q.j, q.k, q.w].map(|x| self.value(x)),
        )
    }
}
