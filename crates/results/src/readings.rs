//! Columns that name a reading of the paper (issue 72): one of our configurations followed by
//! the choices the paper leaves open, `mcor:sightings=all`, `avc:gate=3dof`,
//! `mcor:paper` (the paper's stated mechanisms together), so that readings stand side by side
//! in one sweep as columns with their own headings. The settings themselves live in slam-core
//! (`McorParams::sightings`, `verdict`, `scope`, `depth_normalised`; `AvcParams::gate`,
//! `b_role`); a column only overlays them on the sweep's configuration.

use crate::columns::{ConfigKind, RunConfig};
use anyhow::{bail, Context, Result};
use slam_core::system::{AvcGate, BaselineRole, Config, Scope, Sightings, Verdict};

/// The keys a reading column may set, in the order its canonical name spells them.
pub const READING_KEYS: [&str; 7] = [
    "sightings",
    "verdict",
    "scope",
    "units",
    "tau",
    "gate",
    "b_role",
];

/// The readings one column sets; `None`: the sweep's configuration decides.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Readings {
    /// MC-OR's `sightings`.
    pub sightings: Option<Sightings>,
    /// MC-OR's `verdict`.
    pub verdict: Option<Verdict>,
    /// MC-OR's `scope`.
    pub scope: Option<Scope>,
    /// MC-OR's thresholds relative to depth (`units=depth`, `depth_normalised`) or in metres.
    pub depth_units: Option<bool>,
    /// MC-OR's thresholds (tau_MF, tau_GF, tau_MG) for this column, overriding the sweep's grid.
    pub tau: Option<(f64, f64, f64)>,
    /// AVC's `gate`.
    pub gate: Option<AvcGate>,
    /// `b_role`: AVC's, or, on the baseline, b as the RGB-D camera's baseline (the sweep's
    /// `--baseline` values then apply to it).
    pub b_role: Option<BaselineRole>,
}

/// A column of ours with readings: its configuration kind and what it sets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReadingColumn {
    /// The configuration the readings apply to.
    pub kind: ConfigKind,
    /// The readings.
    pub readings: Readings,
}

impl ReadingColumn {
    /// Parses `base:key=value[:key=value...]` (or `base:paper`). `None` when `s` names no
    /// reading (no `:`); an error naming the allowed keys or values otherwise.
    pub fn parse(s: &str) -> Result<Option<ReadingColumn>> {
        let Some((base, rest)) = s.trim().split_once(':') else {
            return Ok(None);
        };
        let kind = ConfigKind::parse(base)?;
        let mut r = Readings::default();
        for part in rest.split(':') {
            let part = part.trim();
            if part == "paper" {
                r.sightings = Some(Sightings::All);
                r.verdict = Some(Verdict::Consensus);
                r.scope = Some(Scope::TrackingMapping);
                continue;
            }
            let (key, value) = part.split_once('=').with_context(|| {
                format!(
                    "reading {part:?} of column {s:?}: expected key=value (keys: {}) or `paper`",
                    READING_KEYS.join(", ")
                )
            })?;
            set(&mut r, key.trim(), value.trim())
                .with_context(|| format!("reading {part:?} of column {s:?}"))?;
        }
        let c = ReadingColumn { kind, readings: r };
        c.check().with_context(|| format!("column {s:?}"))?;
        Ok(Some(c))
    }

    /// Whether the readings fit the configuration: MC-OR's only where MC-OR is on, AVC's gate
    /// only with AVC, `units=depth` only with its own thresholds.
    fn check(&self) -> Result<()> {
        let r = &self.readings;
        let mcor_keys = r.sightings.is_some()
            || r.verdict.is_some()
            || r.scope.is_some()
            || r.depth_units.is_some()
            || r.tau.is_some();
        if mcor_keys && !self.kind.mcor() {
            bail!("MC-OR's readings need a configuration with MC-OR (mcor, mcor+avc, ...)");
        }
        if r.gate.is_some() && !self.kind.avc() {
            bail!("gate is AVC's: it needs a configuration with AVC (avc, mcor+avc, ...)");
        }
        if r.b_role.is_some() && !self.kind.avc() && self.kind != ConfigKind::Orb {
            bail!("b_role needs AVC, or the baseline orb (b as its camera's baseline)");
        }
        if r.depth_units == Some(true) && r.tau.is_none() {
            bail!(
                "units=depth makes the thresholds fractions of depth: give them with \
                 tau=MF/GF/MG (the metre defaults 0.7/0.7/0.5 would be 70 % of the depth)"
            );
        }
        Ok(())
    }

    /// The canonical spelling (`runs.csv`'s key): the base, then every set key in
    /// [`READING_KEYS`] order.
    pub fn name(&self) -> String {
        let mut s = self.kind.name().to_string();
        for (key, value) in self.pairs() {
            s += &format!(":{key}={value}");
        }
        s
    }

    /// The set readings as (key, value) in [`READING_KEYS`] order.
    fn pairs(&self) -> Vec<(&'static str, String)> {
        let r = &self.readings;
        let mut v = Vec::new();
        if let Some(x) = r.sightings {
            v.push(("sightings", x.name().to_string()));
        }
        if let Some(x) = r.verdict {
            v.push(("verdict", x.name().to_string()));
        }
        if let Some(x) = r.scope {
            v.push(("scope", x.name().to_string()));
        }
        if let Some(x) = r.depth_units {
            v.push(("units", if x { "depth" } else { "metres" }.to_string()));
        }
        if let Some((a, b, c)) = r.tau {
            v.push(("tau", format!("{a}/{b}/{c}")));
        }
        if let Some(x) = r.gate {
            v.push(("gate", x.name().to_string()));
        }
        if let Some(x) = r.b_role {
            v.push(("b_role", x.name().to_string()));
        }
        v
    }

    /// The sweep column this reading is.
    pub fn run_config(&self) -> RunConfig {
        RunConfig::Reading {
            kind: self.kind,
            name: self.name(),
        }
    }

    /// The readings as a table heading's suffix: `sightings all, verdict consensus`.
    pub fn label(&self) -> String {
        self.pairs()
            .iter()
            .map(|(k, v)| format!("{} {v}", k.replace('_', " ")))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Whether the sweep's `--baseline` values apply to this column: AVC's b, or b as the
    /// baseline's camera baseline.
    pub fn takes_baseline(&self) -> bool {
        self.kind.avc() || self.readings.b_role == Some(BaselineRole::Camera)
    }

    /// Overlays the readings on a run's configuration `c` (whose techniques the column's kind
    /// switched on already); `b` is the run's AVC / camera baseline when it has one.
    pub fn apply(&self, c: &mut Config, b: Option<f64>) {
        let r = &self.readings;
        if let Some(m) = c.mcor.as_mut() {
            m.sightings = r.sightings.unwrap_or(m.sightings);
            m.verdict = r.verdict.unwrap_or(m.verdict);
            m.scope = r.scope.unwrap_or(m.scope);
            m.depth_normalised = r.depth_units.unwrap_or(m.depth_normalised);
            if let Some((mf, gf, mg)) = r.tau {
                (m.tau_mf, m.tau_gf, m.tau_mg) = (mf, gf, mg);
            }
        }
        if let Some(a) = c.avc.as_mut() {
            a.gate = r.gate.unwrap_or(a.gate);
            a.b_role = r.b_role.unwrap_or(a.b_role);
        } else if r.b_role == Some(BaselineRole::Camera) {
            c.rgbd_baseline = b.or(c.rgbd_baseline);
        }
    }
}

/// The readings of a sweep column, when it names some.
pub fn of(config: &RunConfig) -> Option<ReadingColumn> {
    match config {
        RunConfig::Reading { name, .. } => ReadingColumn::parse(name).ok().flatten(),
        _ => None,
    }
}

/// Parses a column of `--configs` that is ours: one of our configurations, with readings or
/// without; `None` when `s` names neither (an external system's name, or a mistake).
pub fn parse_column(s: &str) -> Result<Option<RunConfig>> {
    if let Some(c) = ReadingColumn::parse(s)? {
        return Ok(Some(c.run_config()));
    }
    Ok(ConfigKind::parse(s).ok().map(RunConfig::Ours))
}

/// Sets `key` to `value` in `r`, naming the allowed values when `value` is not one.
fn set(r: &mut Readings, key: &str, value: &str) -> Result<()> {
    fn pick<T: Copy>(key: &str, value: &str, allowed: &[(&str, T)]) -> Result<T> {
        allowed
            .iter()
            .find(|(n, _)| *n == value)
            .map(|(_, v)| *v)
            .with_context(|| {
                let names: Vec<&str> = allowed.iter().map(|(n, _)| *n).collect();
                format!("{key} = {value:?}: expected {}", names.join(" or "))
            })
    }
    match key {
        "sightings" => {
            r.sightings = Some(pick(
                key,
                value,
                &[("inliers", Sightings::Inliers), ("all", Sightings::All)],
            )?)
        }
        "verdict" => {
            r.verdict = Some(pick(
                key,
                value,
                &[
                    ("filter", Verdict::Filter),
                    ("consensus", Verdict::Consensus),
                ],
            )?)
        }
        "scope" => {
            r.scope = Some(pick(
                key,
                value,
                &[
                    ("tracking", Scope::Tracking),
                    ("tracking+mapping", Scope::TrackingMapping),
                ],
            )?)
        }
        "units" => r.depth_units = Some(pick(key, value, &[("metres", false), ("depth", true)])?),
        "tau" => {
            let v: Vec<f64> = value
                .split('/')
                .map(|x| x.trim().parse::<f64>())
                .collect::<std::result::Result<_, _>>()
                .ok()
                .filter(|v: &Vec<f64>| v.len() == 3 && v.iter().all(|x| *x > 0.0 && x.is_finite()))
                .with_context(|| {
                    format!("tau = {value:?}: expected three positive numbers MF/GF/MG")
                })?;
            r.tau = Some((v[0], v[1], v[2]));
        }
        "gate" => {
            r.gate = Some(pick(
                key,
                value,
                &[("4dof", AvcGate::FourDof), ("3dof", AvcGate::ThreeDof)],
            )?)
        }
        "b_role" => {
            r.b_role = Some(pick(
                key,
                value,
                &[
                    ("residual", BaselineRole::Residual),
                    ("camera", BaselineRole::Camera),
                ],
            )?)
        }
        other => bail!(
            "unknown reading {other:?}; expected one of {}",
            READING_KEYS.join(", ")
        ),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use slam_core::system::{AvcParams, McorParams};

    #[test]
    fn a_column_spells_its_readings_in_one_canonical_order() {
        let c = ReadingColumn::parse("mcor:scope=tracking+mapping:sightings=all")
            .unwrap()
            .unwrap();
        assert_eq!(c.kind, ConfigKind::Mcor);
        assert_eq!(c.name(), "mcor:sightings=all:scope=tracking+mapping");
        assert_eq!(c.label(), "sightings all, scope tracking+mapping");
        let paper = ReadingColumn::parse("mcor+avc:paper").unwrap().unwrap();
        assert_eq!(
            paper.name(),
            "mcor+avc:sightings=all:verdict=consensus:scope=tracking+mapping"
        );
        assert_eq!(ReadingColumn::parse("mcor").unwrap(), None);
    }

    #[test]
    fn a_reading_that_does_not_fit_is_refused_naming_what_would() {
        let e = format!(
            "{:#}",
            ReadingColumn::parse("mcor:verdict=vote").unwrap_err()
        );
        assert!(e.contains("filter or consensus"), "{e}");
        let e = format!("{:#}", ReadingColumn::parse("mcor:colour=red").unwrap_err());
        assert!(e.contains("sightings, verdict"), "{e}");
        let e = format!(
            "{:#}",
            ReadingColumn::parse("avc:sightings=all").unwrap_err()
        );
        assert!(e.contains("need a configuration with MC-OR"), "{e}");
        let e = format!("{:#}", ReadingColumn::parse("mcor:gate=3dof").unwrap_err());
        assert!(e.contains("AVC"), "{e}");
        let e = format!(
            "{:#}",
            ReadingColumn::parse("mcor:units=depth").unwrap_err()
        );
        assert!(e.contains("tau=MF/GF/MG"), "{e}");
        assert!(ReadingColumn::parse("mcor:units=depth:tau=0.1/0.1/0.07").is_ok());
    }

    #[test]
    fn the_readings_overlay_the_run_configuration() {
        let mut c = Config {
            mcor: Some(McorParams::default()),
            avc: Some(AvcParams::default()),
            ..Config::default()
        };
        ReadingColumn::parse("mcor+avc:paper:gate=3dof:b_role=camera")
            .unwrap()
            .unwrap()
            .apply(&mut c, Some(0.05));
        let m = c.mcor.as_ref().unwrap();
        assert_eq!(
            (m.sightings, m.verdict, m.scope),
            (Sightings::All, Verdict::Consensus, Scope::TrackingMapping)
        );
        let a = c.avc.as_ref().unwrap();
        assert_eq!(
            (a.gate, a.b_role),
            (AvcGate::ThreeDof, BaselineRole::Camera)
        );
        // On the baseline, b_role = camera makes the run's b the camera's baseline.
        let mut orb = Config::default();
        let col = ReadingColumn::parse("orb:b_role=camera").unwrap().unwrap();
        assert!(col.takes_baseline());
        col.apply(&mut orb, Some(0.05));
        assert_eq!(orb.rgbd_baseline, Some(0.05));
        assert_eq!(orb.check(), Ok(()));
    }
}
