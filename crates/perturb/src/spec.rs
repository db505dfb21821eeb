//! The spelling a command line uses: chains `family:level[+family:level...]` (a named camera
//! chain `kinect-fr1:1` standing for its members) and sweep axes `family:LEVELS`.

use crate::chains::NamedChain;
pub use crate::family::{Domain, Family, Perturbation};
use crate::PerturbError;
use slam_core::SensorKind;
use std::fmt;

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
                expected: "family:level or chain:level, e.g. depth-axial:2 or kinect-fr1:1".into(),
            })?;
            let subject = Subject::parse(name)?;
            let level = parse_number(level)?;
            subject.check_level(level)?;
            out.extend(subject.at(level));
        }
        Ok(Chain(out))
    }

    /// The named chain and level whose members this chain is (in any order), if it is one:
    /// what a table prints for a sweep that recorded a chain's members (`kinect-fr1:2` rather
    /// than its nine members).
    pub fn named(&self) -> Option<(NamedChain, f64)> {
        let spelled = self.effective().to_string();
        NamedChain::ALL.into_iter().find_map(|c| {
            let first = c.members().iter().find(|m| m.level != 0.0)?;
            let p = self.0.iter().find(|p| p.family == first.family)?;
            let level = (p.level / first.level * 1e6).round() / 1e6;
            (level > 0.0 && Chain(c.at(level)).effective().to_string() == spelled)
                .then_some((c, level))
        })
    }

    /// Whether any effective member changes the camera the system is given.
    pub fn touches_calibration(&self) -> bool {
        self.effective()
            .0
            .iter()
            .any(|p| p.family.domain() == Domain::Calibration)
    }

    /// Whether any effective member changes the ground truth a run is scored against.
    pub fn touches_groundtruth(&self) -> bool {
        self.effective()
            .0
            .iter()
            .any(|p| p.family.domain() == Domain::GroundTruth)
    }

    /// Whether every effective member leaves the images and the camera as they are (depth,
    /// time and ground-truth families), so a frame's ORB keypoints and descriptors, placed
    /// by the same camera, are those of the unperturbed frame.
    pub fn keeps_images(&self) -> bool {
        self.effective().0.iter().all(|p| {
            matches!(
                p.family.domain(),
                Domain::Depth | Domain::Time | Domain::GroundTruth
            )
        })
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

/// What an axis or a chain member names: one family, a named camera chain whose level
/// multiplies all its members, or a named chain without one of its members (`kinect-fr1~ir-
/// shadow`, for the ablation that says what a member accounts for).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Subject {
    /// One family.
    Family(Family),
    /// A named chain of a real camera's systematic errors.
    Named(NamedChain),
    /// A named chain with one member left out.
    Without(NamedChain, Family),
}

impl Subject {
    /// Parses a family or chain name (`chain~family`: the chain without that member); an
    /// unknown one is refused listing the known ones.
    pub fn parse(s: &str) -> Result<Subject, PerturbError> {
        let s = s.trim();
        let unknown = || PerturbError::UnknownFamily {
            name: s.to_string(),
            known: format!(
                "{}; chains: {}",
                Family::ALL.map(Family::name).join(", "),
                NamedChain::ALL.map(NamedChain::name).join(", ")
            ),
        };
        if let Some((chain, member)) = s.split_once('~') {
            let chain = NamedChain::parse(chain).ok_or_else(unknown)?;
            let family = Family::parse(member)?;
            if !chain.members().iter().any(|m| m.family == family) {
                return Err(PerturbError::Syntax {
                    text: s.to_string(),
                    expected: format!(
                        "a member of {chain}: {}",
                        chain
                            .members()
                            .iter()
                            .map(|m| m.family.name())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                });
            }
            return Ok(Subject::Without(chain, family));
        }
        if let Some(c) = NamedChain::parse(s) {
            return Ok(Subject::Named(c));
        }
        Family::parse(s).map(Subject::Family).map_err(|_| unknown())
    }

    /// The spelling.
    pub fn name(self) -> String {
        match self {
            Subject::Family(f) => f.name().to_string(),
            Subject::Named(c) => c.name().to_string(),
            Subject::Without(c, f) => format!("{c}~{f}"),
        }
    }

    /// Checks a level: the family's range, or for a chain 0 up to the level at which a member
    /// would leave its own range.
    pub fn check_level(self, level: f64) -> Result<(), PerturbError> {
        let chain = match self {
            Subject::Family(f) => return f.check_level(level),
            Subject::Named(c) | Subject::Without(c, _) => c,
        };
        let hi = (chain.max_level() * 1000.0).floor() / 1000.0;
        if !level.is_finite() || !(0.0..=hi).contains(&level) {
            return Err(PerturbError::LevelOutOfRange {
                family: chain.name(),
                level,
                range: format!("0 to {hi} (x the literature's levels)"),
            });
        }
        Ok(())
    }

    /// The members `subject:level` stands for.
    pub fn at(self, level: f64) -> Vec<Perturbation> {
        match self {
            Subject::Family(family) => vec![Perturbation { family, level }],
            Subject::Named(c) => c.at(level),
            Subject::Without(c, f) => c.at(level).into_iter().filter(|p| p.family != f).collect(),
        }
    }

    /// Whether `level` changes nothing.
    pub fn is_identity(self, level: f64) -> bool {
        self.at(level).iter().all(|p| p.family.is_identity(p.level))
    }
}

impl fmt::Display for Subject {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

/// The axes of an ablation of named chain `chain` at `level`: the chain itself, each member
/// alone at its level in the chain, and the chain without each member, every axis at 0 and
/// `level` (so the unperturbed point is shared): what closes a gap, and which member accounts
/// for it.
pub fn ablation_axes(chain: NamedChain, level: f64) -> Vec<Axis> {
    let mut axes = vec![Axis {
        subject: Subject::Named(chain),
        levels: vec![0.0, level],
    }];
    for p in chain.at(level) {
        axes.push(Axis {
            subject: Subject::Family(p.family),
            levels: vec![0.0, p.level],
        });
    }
    for m in chain.members() {
        axes.push(Axis {
            subject: Subject::Without(chain, m.family),
            levels: vec![0.0, level],
        });
    }
    axes
}

/// One axis of a sweep: a family or named chain and the levels to try
/// (`depth-axial:0,1,2,4,8`, `image-noise:0:20:5`, a range start:stop:step with stop
/// included, or `kinect-fr1:0,0.5,1,2`).
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// The family or chain.
    pub subject: Subject,
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
        let subject = Subject::parse(name)?;
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
            subject.check_level(l)?;
        }
        let mut unique: Vec<f64> = Vec::new();
        for l in levels {
            if !unique.contains(&l) {
                unique.push(l);
            }
        }
        Ok(Axis {
            subject,
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
