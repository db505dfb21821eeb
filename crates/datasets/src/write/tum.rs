//! The text files of the TUM RGB-D layout: `rgb.txt`, `depth.txt` (`timestamp filename`),
//! `associations.txt` (`t_rgb rgb/x.png t_depth depth/y.png`, the pairs TUM's associate.py
//! finds) and `groundtruth.txt` (`timestamp tx ty tz qx qy qz qw`), as the readers in
//! [`crate::tum`] read them back. The images beside them are written with
//! [`super::files::png`] and [`super::files::depth_png`].

use std::fmt::Write as _;
use std::path::Path;

use nalgebra::Isometry3;

use super::files::text;
use super::Digits;
use crate::DatasetError;

/// One image of a TUM list: its stamp in seconds and its file, relative to the folder
/// (`rgb/1305031102.175304.png`).
#[derive(Clone, Debug, PartialEq)]
pub struct TumEntry {
    /// Capture time in seconds.
    pub stamp: f64,
    /// Path relative to the sequence folder.
    pub file: String,
}

/// Everything the text files of a TUM folder say.
#[derive(Clone, Debug)]
pub struct TumLists {
    /// What the folder holds, for the lists' `# file:` line (TUM names the bag there).
    pub title: String,
    /// True when the images of `rgb.txt` are colour (`# color images`), false for grey.
    pub colour: bool,
    /// The images of `rgb.txt`, in time order.
    pub rgb: Vec<TumEntry>,
    /// The depth maps of `depth.txt`, in time order.
    pub depth: Vec<TumEntry>,
    /// `associations.txt`: pairs of indices into `rgb` and `depth`.
    pub associations: Vec<(usize, usize)>,
    /// `groundtruth.txt`: camera-to-world poses (T_world_camera) with their stamps; none
    /// written when `None`.
    pub groundtruth: Option<Vec<(f64, Isometry3<f64>)>>,
    /// How stamps and poses are printed.
    pub digits: Digits,
}

/// A stamp as the lists print it.
pub fn stamp_text(t: f64, digits: Digits) -> String {
    match digits {
        Digits::Dataset => format!("{t:.6}"),
        Digits::Exact => format!("{t}"),
    }
}

/// One line of a TUM trajectory, `timestamp tx ty tz qx qy qz qw`: with [`Digits::Dataset`]
/// 9 decimals and the quaternion's sign chosen so qw >= 0, with [`Digits::Exact`] every digit
/// of the pose as it is.
pub fn pose_line(t: f64, pose: &Isometry3<f64>, digits: Digits) -> String {
    let ([x, y, z], [qx, qy, qz, qw]) = digits.pose_values(pose);
    format!("{} {x} {y} {z} {qx} {qy} {qz} {qw}", stamp_text(t, digits))
}

/// Writes `rgb.txt`, `depth.txt`, `associations.txt` and (when there is one) `groundtruth.txt`
/// into `root`. Pairs that name an image outside the lists are refused (a caller bug, reported
/// rather than written).
pub fn write_lists(root: &Path, lists: &TumLists) -> Result<(), DatasetError> {
    let what = &lists.title;
    let kind = if lists.colour { "color" } else { "grey" };
    let mut rgb = format!("# {kind} images\n# file: '{what}'\n# timestamp filename\n");
    let mut depth = format!("# depth maps\n# file: '{what}'\n# timestamp filename\n");
    // Infallible: writing into a String.
    for e in &lists.rgb {
        let _ = writeln!(rgb, "{} {}", stamp_text(e.stamp, lists.digits), e.file);
    }
    for e in &lists.depth {
        let _ = writeln!(depth, "{} {}", stamp_text(e.stamp, lists.digits), e.file);
    }
    let mut assoc = String::new();
    for &(i, j) in &lists.associations {
        let (Some(a), Some(b)) = (lists.rgb.get(i), lists.depth.get(j)) else {
            return Err(DatasetError::invalid(
                root.join("associations.txt"),
                format!("pair ({i}, {j}) outside the lists"),
            ));
        };
        let _ = writeln!(
            assoc,
            "{} {} {} {}",
            stamp_text(a.stamp, lists.digits),
            a.file,
            stamp_text(b.stamp, lists.digits),
            b.file
        );
    }
    text(&root.join("rgb.txt"), &rgb)?;
    text(&root.join("depth.txt"), &depth)?;
    if let Some(gt) = &lists.groundtruth {
        let mut s = format!(
            "# ground truth trajectory\n# file: '{what}'\n# timestamp tx ty tz qx qy qz qw\n"
        );
        for (t, pose) in gt {
            let _ = writeln!(s, "{}", pose_line(*t, pose, lists.digits));
        }
        text(&root.join("groundtruth.txt"), &s)?;
    }
    text(&root.join("associations.txt"), &assoc)
}
