//! The taxonomy: every perturbation family, what one level of it means, its valid range, and
//! the spelling `family:level[+family:level...]` a command line uses.

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
}

impl Family {
    /// Every family, in the taxonomy's order.
    pub const ALL: [Family; 15] = [
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
            | Family::RgbDepthOffset => Domain::Depth,
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

/// Perturbations applied in order (`depth-axial:2+depth-lateral:2`). Empty: none.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Chain(pub Vec<Perturbation>);

impl Chain {
    /// Parses `family:level[+family:level...]`; `none` or an empty string is the empty chain.
    /// Every level is checked against its family's range.
    pub fn parse(s: &str) -> Result<Chain, PerturbError> {
        let s = s.trim();
        if s.is_empty() || s == "none" {
            return Ok(Chain::default());
        }
        let mut out = Vec::new();
        for part in s.split('+') {
            let (name, level) = part.split_once(':').ok_or_else(|| PerturbError::Syntax {
                text: part.trim().to_string(),
                expected: "family:level, e.g. depth-axial:2".into(),
            })?;
            let family = Family::parse(name)?;
            let level = parse_number(level)?;
            family.check_level(level)?;
            out.push(Perturbation { family, level });
        }
        Ok(Chain(out))
    }

    /// The chain without its identity members (what is actually applied).
    pub fn effective(&self) -> Chain {
        Chain(
            self.0
                .iter()
                .filter(|p| !p.family.is_identity(p.level))
                .copied()
                .collect(),
        )
    }

    /// Whether nothing changes the frames.
    pub fn is_identity(&self) -> bool {
        self.effective().0.is_empty()
    }

    /// Refuses families that do not apply to `sensor` (a depth perturbation on a stereo
    /// sequence), naming the sequence.
    pub fn check_sensor(&self, sensor: SensorKind, sequence: &str) -> Result<(), PerturbError> {
        for p in &self.0 {
            if !p.family.applies_to(sensor) {
                return Err(PerturbError::WrongSensor {
                    family: p.family.name(),
                    sequence: sequence.to_string(),
                    sensor: match sensor {
                        SensorKind::Rgbd => "RGB-D",
                        SensorKind::Stereo => "stereo",
                    },
                });
            }
        }
        Ok(())
    }

    /// Whether every effective member acts on depth only, so a frame's ORB keypoints and
    /// descriptors are those of the unperturbed frame.
    pub fn depth_only(&self) -> bool {
        self.effective()
            .0
            .iter()
            .all(|p| p.family.domain() == Domain::Depth)
    }
}

impl fmt::Display for Chain {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_empty() {
            return f.write_str("none");
        }
        let parts: Vec<String> = self.0.iter().map(Perturbation::to_string).collect();
        f.write_str(&parts.join("+"))
    }
}

/// One axis of a sweep: a family and the levels to try (`depth-axial:0,1,2,4,8` or
/// `image-noise:0:20:5`, a range start:stop:step with stop included).
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// The family.
    pub family: Family,
    /// Its levels, in the order given (tables follow it: put the mildest first).
    pub levels: Vec<f64>,
}

impl Axis {
    /// Parses `family:LEVELS` with LEVELS a list `0,1,2` or a range `0:20:5`.
    pub fn parse(s: &str) -> Result<Axis, PerturbError> {
        let (name, levels) = s
            .trim()
            .split_once(':')
            .ok_or_else(|| PerturbError::Syntax {
                text: s.trim().to_string(),
                expected: "family:LEVELS, e.g. depth-axial:0,1,2,4 or image-noise:0:20:5".into(),
            })?;
        let family = Family::parse(name)?;
        let levels = if levels.contains(':') {
            let parts: Vec<&str> = levels.split(':').collect();
            if parts.len() != 3 {
                return Err(PerturbError::Syntax {
                    text: levels.to_string(),
                    expected: "a range start:stop:step".into(),
                });
            }
            let (a, b, step) = (
                parse_number(parts[0])?,
                parse_number(parts[1])?,
                parse_number(parts[2])?,
            );
            if step <= 0.0 || b < a || (b - a) / step > 10_000.0 {
                return Err(PerturbError::Syntax {
                    text: levels.to_string(),
                    expected: "step > 0, stop >= start, at most 10000 levels".into(),
                });
            }
            let n = ((b - a) / step + 1e-9).floor() as usize;
            (0..=n)
                .map(|k| ((a + k as f64 * step) * 1e9).round() / 1e9)
                .collect()
        } else {
            levels
                .split(',')
                .filter(|t| !t.trim().is_empty())
                .map(parse_number)
                .collect::<Result<Vec<f64>, _>>()?
        };
        if levels.is_empty() {
            return Err(PerturbError::Syntax {
                text: s.to_string(),
                expected: "at least one level".into(),
            });
        }
        for &l in &levels {
            family.check_level(l)?;
        }
        let mut unique: Vec<f64> = Vec::new();
        for l in levels {
            if !unique.contains(&l) {
                unique.push(l);
            }
        }
        Ok(Axis {
            family,
            levels: unique,
        })
    }
}

fn parse_number(t: &str) -> Result<f64, PerturbError> {
    t.trim().parse::<f64>().map_err(|_| PerturbError::Syntax {
        text: t.trim().to_string(),
        expected: "a number".into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chains_parse_print_and_refuse() {
        let c = Chain::parse("depth-axial:2+depth-lateral:1.5").unwrap();
        assert_eq!(c.to_string(), "depth-axial:2+depth-lateral:1.5");
        assert_eq!(Chain::parse(&c.to_string()).unwrap(), c);
        assert!(Chain::parse("none").unwrap().is_identity());
        assert!(Chain::parse("depth-axial:0+frame-drop:1")
            .unwrap()
            .is_identity());
        let e = Chain::parse("depth-noise:2").unwrap_err().to_string();
        assert!(
            e.contains("unknown perturbation \"depth-noise\"") && e.contains("depth-axial"),
            "{e}"
        );
        let e = Chain::parse("depth-holes:120").unwrap_err().to_string();
        assert!(e.contains("120") && e.contains("0 to 99"), "{e}");
        let e = Chain::parse("frame-drop:2.5").unwrap_err().to_string();
        assert!(e.contains("whole number"), "{e}");
        assert!(Chain::parse("depth-axial").is_err());
        assert!(Chain::parse("depth-axial:nan").is_err());
        let e = Chain::parse("depth-axial:1")
            .unwrap()
            .check_sensor(SensorKind::Stereo, "stereo")
            .unwrap_err()
            .to_string();
        assert!(e.contains("depth-axial") && e.contains("stereo"), "{e}");
        assert!(Chain::parse("stereo-misalignment:0.2")
            .unwrap()
            .check_sensor(SensorKind::Rgbd, "kinect")
            .is_err());
        assert!(Chain::parse("depth-axial:1+depth-lag:2")
            .unwrap()
            .depth_only());
        assert!(!Chain::parse("depth-axial:1+jpeg:50").unwrap().depth_only());
    }

    #[test]
    fn axes_lists_and_ranges() {
        let a = Axis::parse("image-noise:0:20:5").unwrap();
        assert_eq!(a.levels, vec![0.0, 5.0, 10.0, 15.0, 20.0]);
        let a = Axis::parse("depth-axial:0,1,2,4,8,2").unwrap();
        assert_eq!(a.levels, vec![0.0, 1.0, 2.0, 4.0, 8.0]);
        assert!(Axis::parse("depth-axial:0:8").is_err());
        assert!(Axis::parse("occluders:0,1.5").is_err());
        assert!(Axis::parse("jpeg:0,101").is_err());
    }
}
