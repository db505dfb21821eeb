//! Named camera chains: a real camera's systematic errors together, each member at the level the
//! literature gives (or, where no published figure was found, an estimate that says so), so a
//! twin can be made as hard as the real sequence without tuning anything. A chain's level
//! multiplies every member's: `kinect-fr1:0` is nothing, `:1` the literature's camera, `:2` one
//! twice as bad.
//!
//! Members are listed in the order a real sensor applies them: shadows where the projector
//! cannot see, the depth conversion's distortion and scale, registration to colour; then the
//! calibration the system is given; then the ground truth's own errors.
//!
//! Left out, because the twins render them already (`synth::catalog::twins`), so a chain on a
//! twin would count them twice: `disparity-quantization` (the twins' Kinect depth model rounds
//! disparity to 1/8 px after Nguyen's axial noise, as ICL-NUIM's simulator does) and
//! `gt-jitter` (the twins' ground truth carries the white motion-capture noise measured on the
//! real files: 0.2 mm per axis for TUM, from fr2_desk's `groundtruth.txt`; 1 mm for EuRoC's
//! Vicon). Both families stay for inputs that lack them.

use crate::family::{Family, Perturbation};
use std::fmt;

/// One member of a named chain: a family, its level at chain level 1, and where the level
/// comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Member {
    /// The family.
    pub family: Family,
    /// Its level at chain level 1, in the family's unit.
    pub level: f64,
    /// The source of the level (paper, page or file), or "estimate" with the reason.
    pub source: &'static str,
}

/// A named chain of a real camera's systematic errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NamedChain {
    /// TUM freiburg1's Kinect v1.
    KinectFr1,
    /// TUM freiburg2's Kinect v1.
    KinectFr2,
    /// TUM freiburg3's Asus Xtion (PrimeSense, the same structured-light design).
    KinectFr3,
    /// EuRoC's VI-sensor stereo pair with Vicon / Leica ground truth.
    Euroc,
}

const SHADOW: &str = "Kinect v1 projector-to-IR-camera baseline 7.5 cm (Khoshelham & Elberink, \
    Sensors 2012; ROS kinect_calibration/technical)";
const DISTORT: &str = "estimate: accurate to about 3 m, distortion growing beyond (Teichman, \
    Miller & Thrun, RSS 2013); about 1-2 % below 3 m (Herrera et al., PAMI 2012)";
const REGISTER: &str = "estimate: no measured figure found; ICL-NUIM shifts depth by 0.5 px \
    sigma, factory registrations are reported off by a few px";
const FOCAL: &str = "estimate: checkerboard calibration uncertainty of a VGA camera, 0.2-0.5 % \
    (no published figure for TUM's calibration found)";
const PP: &str = "estimate: checkerboard calibration uncertainty, 1-3 px (no published figure \
    for TUM's calibration found)";
const DIST_LEFT: &str = "estimate: a tenth of the radial model left out (no published \
    uncertainty of TUM's k1, k2, k3 found)";
const GT_OFFSET: &str = "estimate: TUM calls its 100 Hz motion capture time-synchronised \
    (Sturm et al., IROS 2012) without a residual; a few ms";
const HAND_EYE: &str = "estimate: a hand-eye calibration off by a few mm and below 1 degree";

/// A member of a named chain at `level`, `source` saying where the level comes from.
const fn member(family: Family, level: f64, source: &'static str) -> Member {
    Member {
        family,
        level,
        source,
    }
}

const IR_SHADOW: Member = member(Family::IrShadow, 1.0, SHADOW);
const DEPTH_DISTORTION: Member = member(Family::DepthDistortion, 1.5, DISTORT);
const DEPTH_REGISTRATION: Member = member(Family::DepthRegistration, 1.0, REGISTER);
const FOCAL_ERROR: Member = member(Family::FocalError, 0.5, FOCAL);
const PRINCIPAL_POINT_ERROR: Member = member(Family::PrincipalPointError, 2.0, PP);
const DISTORTION_ERROR: Member = member(Family::DistortionError, 0.1, DIST_LEFT);
const GT_OFFSET_KINECT: Member = member(Family::GtOffset, 3.0, GT_OFFSET);
const GT_HAND_EYE: Member = member(Family::GtHandEye, 1.0, HAND_EYE);

const FR1: &[Member] = &[
    IR_SHADOW,
    DEPTH_DISTORTION,
    member(
        Family::DepthScale,
        -3.381642512,
        "TUM's depth correction 1.035 for fr1 (TUM RGB-D file formats page), which \
            ORB-SLAM2's TUM1.yaml does not apply (DepthMapFactor 5000): depth read 1/1.035 - 1 \
            = -3.38 %",
    ),
    DEPTH_REGISTRATION,
    FOCAL_ERROR,
    PRINCIPAL_POINT_ERROR,
    DISTORTION_ERROR,
    GT_OFFSET_KINECT,
    GT_HAND_EYE,
];

const FR2: &[Member] = &[
    IR_SHADOW,
    DEPTH_DISTORTION,
    member(
        Family::DepthScale,
        -1.017665131,
        "TUM's depth correction 1.031 for fr2 against ORB-SLAM2's TUM2.yaml \
            DepthMapFactor 5208 (1.0416): depth read 1.031 / 1.0416 - 1 = -1.02 % (the sign \
            assumed as fr1's)",
    ),
    DEPTH_REGISTRATION,
    FOCAL_ERROR,
    PRINCIPAL_POINT_ERROR,
    DISTORTION_ERROR,
    GT_OFFSET_KINECT,
    GT_HAND_EYE,
];

const FR3: &[Member] = &[
    member(
        Family::IrShadow,
        1.0,
        "the Xtion's PrimeSense design, projector-camera baseline taken as the \
            Kinect's 7.5 cm (estimate)",
    ),
    DEPTH_DISTORTION,
    DEPTH_REGISTRATION,
    FOCAL_ERROR,
    PRINCIPAL_POINT_ERROR,
    GT_OFFSET_KINECT,
    GT_HAND_EYE,
];

const EUROC: &[Member] = &[
    member(
        Family::StereoMisalignment,
        0.03,
        "estimate: a Kalibr stereo calibration's reprojection error of 0.1-0.3 px is \
            about 0.2 px / 458 px = 0.025 degrees of rotation",
    ),
    member(
        Family::FocalError,
        0.2,
        "estimate: a Kalibr calibration of a 752x480 camera, 0.1-0.3 %",
    ),
    member(
        Family::PrincipalPointError,
        1.0,
        "estimate: a Kalibr calibration, about 1 px",
    ),
    member(
        Family::GtOffset,
        1.0,
        "estimate: EuRoC's ground truth is a batch fit of Vicon / Leica and IMU with \
            its time offset estimated (sensor.yaml of state_groundtruth_estimate0); residual \
            not published",
    ),
    GT_HAND_EYE,
];

impl NamedChain {
    /// Every named chain.
    pub const ALL: [NamedChain; 4] = [
        NamedChain::KinectFr1,
        NamedChain::KinectFr2,
        NamedChain::KinectFr3,
        NamedChain::Euroc,
    ];

    /// The command-line spelling.
    pub fn name(self) -> &'static str {
        match self {
            NamedChain::KinectFr1 => "kinect-fr1",
            NamedChain::KinectFr2 => "kinect-fr2",
            NamedChain::KinectFr3 => "kinect-fr3",
            NamedChain::Euroc => "euroc",
        }
    }

    /// The camera it describes, in a sentence.
    pub fn camera(self) -> &'static str {
        match self {
            NamedChain::KinectFr1 => "TUM freiburg1's Kinect v1 (fr1_* sequences)",
            NamedChain::KinectFr2 => "TUM freiburg2's Kinect v1 (fr2_* sequences)",
            NamedChain::KinectFr3 => "TUM freiburg3's Asus Xtion (fr3_* sequences)",
            NamedChain::Euroc => "EuRoC's VI-sensor stereo pair, Vicon / Leica ground truth",
        }
    }

    /// The members at chain level 1, in the order they apply.
    pub fn members(self) -> &'static [Member] {
        match self {
            NamedChain::KinectFr1 => FR1,
            NamedChain::KinectFr2 => FR2,
            NamedChain::KinectFr3 => FR3,
            NamedChain::Euroc => EUROC,
        }
    }

    /// The chain named `s`, if any.
    pub fn parse(s: &str) -> Option<NamedChain> {
        NamedChain::ALL.into_iter().find(|c| c.name() == s.trim())
    }

    /// The members at chain level `level` (each member's level times it, rounded to 1e-9 so
    /// the canonical spelling stays short), unchecked.
    pub fn at(self, level: f64) -> Vec<Perturbation> {
        self.members()
            .iter()
            .map(|m| Perturbation {
                family: m.family,
                level: ((m.level * level) * 1e9).round() / 1e9 + 0.0,
            })
            .collect()
    }

    /// The largest chain level at which every member stays inside its family's range.
    pub fn max_level(self) -> f64 {
        self.members()
            .iter()
            .map(|m| {
                let (lo, hi, _) = m.family.range();
                if m.level > 0.0 {
                    hi / m.level
                } else {
                    lo / m.level
                }
            })
            .fold(f64::INFINITY, f64::min)
    }
}

impl fmt::Display for NamedChain {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn members_are_inside_their_ranges_and_scale_with_the_level() {
        for c in NamedChain::ALL {
            assert!(c.max_level() >= 4.0, "{c}: {}", c.max_level());
            for (m, p) in c.members().iter().zip(c.at(2.0)) {
                m.family.check_level(m.level).unwrap();
                assert_eq!(p.family, m.family);
                assert!((p.level - 2.0 * m.level).abs() < 1e-8, "{c} {}", m.family);
            }
            assert!(c.at(0.0).iter().all(|p| p.level == 0.0));
            assert_eq!(NamedChain::parse(c.name()), Some(c));
        }
        // No depth family in the stereo chain, no calibration of distortion where TUM
        // undistorted the images (fr3) or the reader rectified them (EuRoC).
        for m in NamedChain::Euroc.members() {
            assert!(
                m.family.applies_to(slam_core::SensorKind::Stereo),
                "{}",
                m.family
            );
        }
        for c in [NamedChain::KinectFr3, NamedChain::Euroc] {
            assert!(c
                .members()
                .iter()
                .all(|m| m.family != Family::DistortionError));
        }
    }
}
