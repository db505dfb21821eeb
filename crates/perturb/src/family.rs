//! The taxonomy: every perturbation family, what it acts on, what one level of it means and its
//! valid range.

use crate::PerturbError;
use slam_core::SensorKind;
use std::fmt;

/// What a family acts on (decides which features a sweep can reuse across its levels).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    /// The depth image (RGB-D only); images and stamps untouched.
    Depth,
    /// The grey image(s).
    Image,
    /// Which frames, and their stamps.
    Time,
    /// Objects drawn into images and depth (moving occluders).
    Dynamic,
    /// The stereo rig (stereo only).
    Stereo,
    /// The camera the system is *given* (its settings); the images stay as recorded.
    Calibration,
    /// The ground truth a run is scored against; the input stays as recorded.
    GroundTruth,
}

/// A perturbation family.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Family {
    /// Nguyen et al.'s axial noise at normal incidence, sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2 m,
    /// times the level, added to the measured depth.
    DepthAxial,
    /// Lateral noise: each pixel's depth read from a neighbour offset by N(0, level) pixels in x
    /// and y (mixes fore- and background at boundaries).
    DepthLateral,
    /// Share of the valid depth removed in blobs, percent.
    DepthHoles,
    /// Flying pixels: depths mixed between the two surfaces within `level` pixels of a
    /// discontinuity.
    DepthEdges,
    /// Depth scale bias, percent (z' = z (1 + level / 100)).
    DepthScale,
    /// Depth taken from `level` frames earlier (stamped as the colour image).
    DepthLag,
    /// Signal-dependent sensor noise: its standard deviation at mid-grey (128), grey levels.
    ImageNoise,
    /// Linear motion blur, length in pixels along a per-frame direction.
    MotionBlur,
    /// Per-frame exposure (gain) flicker: standard deviation of the gain, percent.
    Exposure,
    /// JPEG compression at quality `level` (1-100; 0 = none): lower is worse.
    Jpeg,
    /// Keep every `level`-th frame (faster motion at the same frame rate of processing).
    FrameDrop,
    /// Gaussian noise on every frame's stamp, standard deviation in milliseconds.
    StampJitter,
    /// Depth from the frame nearest `level` milliseconds later (negative: earlier) than the
    /// colour image it is paired with.
    RgbDepthOffset,
    /// `level` textured objects moving through the view, with consistent depth (RGB-D) or
    /// disparity (stereo).
    Occluders,
    /// The right camera rotated by `level` degrees about its x axis (an imperfect
    /// rectification: rows no longer correspond).
    StereoMisalignment,
    // The systematic families: a real camera's errors that bundle adjustment cannot average
    // away. New families go at the end: a family's discriminant seeds its draws.
    /// The camera given to the system has fx and fy `level` percent too long (a calibration
    /// error); the images stay exactly as recorded.
    FocalError,
    /// The given camera's principal point is `level` pixels off, in a direction fixed by the
    /// perturbation seed.
    PrincipalPointError,
    /// The given camera leaves out `level` (a share, 1 = all) of the true lens distortion:
    /// k1, k2, p1, p2, k3 become (1 - level) times theirs.
    DistortionError,
    /// A smooth multiplicative depth error that grows with range: `level` percent at 3 m at the
    /// field's extreme; the field is drawn once per sequence from the perturbation seed.
    DepthDistortion,
    /// Depth registered to colour through a smooth warp of `level` pixels (fixed for the
    /// sequence), the nearer surface winning where the warp folds (foreground edges fattened).
    DepthRegistration,
    /// IR shadows: no depth where the projector, `level` x 7.5 cm to the camera's right, cannot
    /// see the surface (a band left of every foreground edge, f b (1/z_fg - 1/z_bg) pixels).
    IrShadow,
    /// Depth measured as disparity on a lattice of `level` x 1/8 px at the Kinect's f b
    /// (43.5 px m), after a sub-step jitter (sigma half a step).
    DisparityQuantization,
    /// The ground truth is stamped `level` ms early: every estimate is scored against the pose
    /// `level` ms after its own stamp (`noisefree eval --offset level/1000` on the clean files).
    GtOffset,
    /// Motion-capture noise: every ground-truth position moved by N(0, `level` mm) per axis.
    GtJitter,
    /// A fixed camera-to-marker (hand-eye) error of `level` mm along and `level` degrees about
    /// directions fixed by the perturbation seed, on every ground-truth pose.
    GtHandEye,
}

impl Family {
    /// Every family, in the taxonomy's order.
    pub const ALL: [Family; 25] = [
        Family::DepthAxial,
        Family::DepthLateral,
        Family::DepthHoles,
        Family::DepthEdges,
        Family::DepthScale,
        Family::DepthLag,
        Family::ImageNoise,
        Family::MotionBlur,
        Family::Exposure,
        Family::Jpeg,
        Family::FrameDrop,
        Family::StampJitter,
        Family::RgbDepthOffset,
        Family::Occluders,
        Family::StereoMisalignment,
        Family::FocalError,
        Family::PrincipalPointError,
        Family::DistortionError,
        Family::DepthDistortion,
        Family::DepthRegistration,
        Family::IrShadow,
        Family::DisparityQuantization,
        Family::GtOffset,
        Family::GtJitter,
        Family::GtHandEye,
    ];

    /// The command-line spelling.
    pub fn name(self) -> &'static str {
        match self {
            Family::DepthAxial => "depth-axial",
            Family::DepthLateral => "depth-lateral",
            Family::DepthHoles => "depth-holes",
            Family::DepthEdges => "depth-edges",
            Family::DepthScale => "depth-scale",
            Family::DepthLag => "depth-lag",
            Family::ImageNoise => "image-noise",
            Family::MotionBlur => "motion-blur",
            Family::Exposure => "exposure",
            Family::Jpeg => "jpeg",
            Family::FrameDrop => "frame-drop",
            Family::StampJitter => "stamp-jitter",
            Family::RgbDepthOffset => "rgb-depth-offset",
            Family::Occluders => "occluders",
            Family::StereoMisalignment => "stereo-misalignment",
            Family::FocalError => "focal-error",
            Family::PrincipalPointError => "principal-point-error",
            Family::DistortionError => "distortion-error",
            Family::DepthDistortion => "depth-distortion",
            Family::DepthRegistration => "depth-registration",
            Family::IrShadow => "ir-shadow",
            Family::DisparityQuantization => "disparity-quantization",
            Family::GtOffset => "gt-offset",
            Family::GtJitter => "gt-jitter",
            Family::GtHandEye => "gt-hand-eye",
        }
    }

    /// Parses the command-line spelling.
    pub fn parse(s: &str) -> Result<Family, PerturbError> {
        let s = s.trim();
        Family::ALL
            .into_iter()
            .find(|f| f.name() == s)
            .ok_or_else(|| PerturbError::UnknownFamily {
                name: s.to_string(),
                known: Family::ALL.map(Family::name).join(", "),
            })
    }

    /// The unit of one level, as tables print it.
    pub fn unit(self) -> &'static str {
        match self {
            Family::DepthAxial => "x Nguyen sigma",
            Family::DepthLateral => "px sigma",
            Family::DepthHoles => "% of depth",
            Family::DepthEdges => "px band",
            Family::DepthScale => "% scale",
            Family::DepthLag => "frames",
            Family::ImageNoise => "grey levels at 128",
            Family::MotionBlur => "px",
            Family::Exposure => "% gain sigma",
            Family::Jpeg => "quality",
            Family::FrameDrop => "keep 1 in n",
            Family::StampJitter => "ms sigma",
            Family::RgbDepthOffset => "ms",
            Family::Occluders => "objects",
            Family::StereoMisalignment => "deg",
            Family::FocalError => "% of fx, fy",
            Family::PrincipalPointError => "px",
            Family::DistortionError => "share left out",
            Family::DepthDistortion => "% at 3 m",
            Family::DepthRegistration => "px warp",
            Family::IrShadow => "x 7.5 cm baseline",
            Family::DisparityQuantization => "x 1/8 px step",
            Family::GtOffset => "ms",
            Family::GtJitter => "mm sigma",
            Family::GtHandEye => "mm and deg",
        }
    }

    /// What the family acts on.
    pub fn domain(self) -> Domain {
        match self {
            Family::DepthAxial
            | Family::DepthLateral
            | Family::DepthHoles
            | Family::DepthEdges
            | Family::DepthScale
            | Family::DepthLag
            | Family::RgbDepthOffset
            | Family::DepthDistortion
            | Family::DepthRegistration
            | Family::IrShadow
            | Family::DisparityQuantization => Domain::Depth,
            Family::FocalError | Family::PrincipalPointError | Family::DistortionError => {
                Domain::Calibration
            }
            Family::GtOffset | Family::GtJitter | Family::GtHandEye => Domain::GroundTruth,
            Family::ImageNoise | Family::MotionBlur | Family::Exposure | Family::Jpeg => {
                Domain::Image
            }
            Family::FrameDrop | Family::StampJitter => Domain::Time,
            Family::Occluders => Domain::Dynamic,
            Family::StereoMisalignment => Domain::Stereo,
        }
    }

    /// The valid levels: inclusive bounds, and whether only whole numbers make sense.
    pub fn range(self) -> (f64, f64, bool) {
        match self {
            Family::DepthAxial => (0.0, 1000.0, false),
            Family::DepthLateral => (0.0, 50.0, false),
            Family::DepthHoles => (0.0, 99.0, false),
            Family::DepthEdges => (0.0, 20.0, true),
            Family::DepthScale => (-50.0, 50.0, false),
            Family::DepthLag => (0.0, 30.0, true),
            Family::ImageNoise => (0.0, 64.0, false),
            Family::MotionBlur => (0.0, 60.0, false),
            Family::Exposure => (0.0, 100.0, false),
            Family::Jpeg => (0.0, 100.0, true),
            Family::FrameDrop => (0.0, 100.0, true),
            Family::StampJitter => (0.0, 1000.0, false),
            Family::RgbDepthOffset => (-1000.0, 1000.0, false),
            Family::Occluders => (0.0, 20.0, true),
            Family::StereoMisalignment => (0.0, 10.0, false),
            Family::FocalError => (-20.0, 20.0, false),
            Family::PrincipalPointError => (0.0, 50.0, false),
            Family::DistortionError => (0.0, 2.0, false),
            Family::DepthDistortion => (0.0, 50.0, false),
            Family::DepthRegistration => (0.0, 50.0, false),
            Family::IrShadow => (0.0, 20.0, false),
            Family::DisparityQuantization => (0.0, 64.0, false),
            Family::GtOffset => (-1000.0, 1000.0, false),
            Family::GtJitter => (0.0, 1000.0, false),
            Family::GtHandEye => (0.0, 90.0, false),
        }
    }

    /// Whether the family applies to a sequence of `sensor`.
    pub fn applies_to(self, sensor: SensorKind) -> bool {
        match self.domain() {
            Domain::Depth => sensor == SensorKind::Rgbd,
            Domain::Stereo => sensor == SensorKind::Stereo,
            _ => true,
        }
    }

    /// Whether `level` leaves frames as they are (level 0; frame-drop 1 keeps every frame;
    /// jpeg 0 is no compression).
    pub fn is_identity(self, level: f64) -> bool {
        level == 0.0 || (self == Family::FrameDrop && level == 1.0)
    }

    /// Checks `level` against the family's range.
    pub fn check_level(self, level: f64) -> Result<(), PerturbError> {
        let (lo, hi, whole) = self.range();
        if !level.is_finite() || level < lo || level > hi || (whole && level.fract() != 0.0) {
            return Err(PerturbError::LevelOutOfRange {
                family: self.name(),
                level,
                range: format!(
                    "{}{lo} to {hi} ({})",
                    if whole { "a whole number from " } else { "" },
                    self.unit()
                ),
            });
        }
        Ok(())
    }
}

impl fmt::Display for Family {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One family at one level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Perturbation {
    /// The family.
    pub family: Family,
    /// Its level, in the family's unit.
    pub level: f64,
}

impl fmt::Display for Perturbation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.family, self.level)
    }
}
