//! ate-eval: trajectory evaluation as the SLAM community does it — absolute trajectory error
//! (ATE) after timestamp association and Umeyama / Horn alignment, and relative pose error
//! (RPE) — giving the same numbers as TUM's `evaluate_ate.py` and `evo_ape` on the same files.
//!
//! Module map, lowest first (a module uses only those before it; `tools/import_graph.py`
//! checks it):
//! - [`error`]: the [`Error`]s of reading and evaluation, and the [`Warning`]s of a reader that
//!   repaired its input; [`trajectory`]: the [`Trajectory`] type (timestamps + SE3 poses) and
//!   frame conversions; [`stats`]: the error statistics of a set of residuals;
//! - [`associate`](mod@associate): nearest-timestamp association (TUM and evo conventions);
//!   [`align`]: closed-form Umeyama alignment (SE3, Sim3);
//! - [`stamps`]: repeated and out-of-order stamps, resolved as each community tool does;
//! - [`io`]: TUM, EuRoC ground-truth CSV and KITTI readers / writers with line-precise errors;
//! - [`ate`], [`rpe`]: absolute and relative pose error.

pub mod align;
pub mod associate;
pub mod ate;
pub mod error;
pub mod io;
pub mod rpe;
pub mod stamps;
pub mod stats;
pub mod trajectory;

pub use align::{umeyama, Alignment, AlignmentMode};
pub use associate::{associate, AssociationMode};
pub use ate::{evaluate_ate, AteOptions, AteResult};
pub use error::{Error, Warning};
pub use rpe::{evaluate_rpe, evaluate_rpe_with, RpeDelta, RpePairs, RpeResult};
pub use stamps::StampPolicy;
pub use stats::ErrorStats;
pub use trajectory::Trajectory;
