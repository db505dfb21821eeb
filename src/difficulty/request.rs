//! What `noisefree match` asks of a bisection, resolved from its flags and the catalog: the
//! chain or family whose level is sought (a twin's camera chain by default), the target ATE
//! (metres, millimetres, or the paper's figure for the row a twin imitates), the highest level
//! tried; and what it leaves behind: `match.json`, `match.csv` and the verdict line.

use super::{MatchResult, MatchStatus};
use anyhow::{bail, Context, Result};
use atomic_file::write as write_atomic;
use datasets::catalog::Entry;
use perturb::{NamedChain, Subject};
use std::path::Path;

/// The chain a twin's camera has, from the name of the sequence it imitates.
pub fn chain_of(imitates: &str) -> Option<NamedChain> {
    let s = imitates.to_ascii_lowercase();
    if s.starts_with("fr1") {
        Some(NamedChain::KinectFr1)
    } else if s.starts_with("fr2") {
        Some(NamedChain::KinectFr2)
    } else if s.starts_with("fr3") {
        Some(NamedChain::KinectFr3)
    } else if s.starts_with('v') || s.starts_with("mh") {
        Some(NamedChain::Euroc)
    } else {
        None
    }
}

/// Parses `0.023`, `23mm`, `0.023m` into metres.
pub fn parse_metres(text: &str) -> Result<f64> {
    let t = text.trim();
    let (num, scale) = match t.strip_suffix("mm") {
        Some(n) => (n, 1e-3),
        None => (t.strip_suffix('m').unwrap_or(t), 1.0),
    };
    let v: f64 = num.trim().parse().map_err(|_| {
        anyhow::anyhow!("--target {t:?}: expected metres (0.023), millimetres (23mm) or `paper`")
    })?;
    if !(v.is_finite() && v > 0.0) {
        bail!("--target {t:?}: must be a positive ATE");
    }
    Ok(v * scale)
}

/// The subject of `--chain`, or without it the camera chain of the sequence a twin imitates
/// (`imitated`); `label` names the sequence in the error.
pub fn subject_of(chain: Option<&str>, imitated: Option<&Entry>, label: &str) -> Result<Subject> {
    match chain {
        Some(c) => Subject::parse(c).context("--chain"),
        None => {
            let named = imitated.and_then(|e| chain_of(&e.name)).with_context(|| {
                format!("--chain: {label} imitates no TUM or EuRoC sequence; name a chain")
            })?;
            Ok(Subject::Named(named))
        }
    }
}

/// The target of `--target` in metres: `paper` is the paper's ORB-SLAM2 figure for the
/// sequence a twin imitates (`imitated`), refused where the paper has none or reports a failure.
pub fn target_of(text: &str, imitated: Option<&Entry>, label: &str) -> Result<f64> {
    if text.trim() != "paper" {
        return parse_metres(text);
    }
    let e = imitated.with_context(|| {
        format!("--target paper: {label} is not a twin of a sequence of the paper")
    })?;
    match e.paper.as_ref().and_then(|p| p.orb_slam2) {
        Some(datasets::catalog::Ate::Metres(m)) => Ok(m),
        Some(datasets::catalog::Ate::Failure) => bail!(
            "--target paper: the paper's ORB-SLAM2 failed on {} ('F'); give a target",
            e.name
        ),
        None => bail!(
            "--target paper: the paper gives no ORB-SLAM2 figure for {}",
            e.name
        ),
    }
}

/// The highest level tried: `--max-level`, or the subject's highest valid level capped at 8;
/// refused when the subject has no such level.
pub fn highest_level(subject: Subject, max_level: Option<f64>) -> Result<f64> {
    let max_valid = match subject {
        Subject::Named(c) | Subject::Without(c, _) => (c.max_level() * 1000.0).floor() / 1000.0,
        Subject::Family(f) => f.range().1,
    };
    let high = max_level.unwrap_or(max_valid.min(8.0));
    subject.check_level(high).context("--max-level")?;
    Ok(high)
}

/// `match.csv`: a row per run of every level measured (run i: perturbation seed
/// `perturb_seed + i`, SLAM seed i), its ATE or empty and `failed`.
pub fn runs_csv(result: &MatchResult, perturb_seed: u64) -> Result<Vec<u8>> {
    let mut csv = csv::Writer::from_writer(Vec::new());
    csv.write_record([
        "step",
        "level",
        "run",
        "perturb_seed",
        "seed",
        "ate_m",
        "failed",
    ])?;
    for (k, s) in result.steps.iter().enumerate() {
        for (i, a) in s.ates.iter().enumerate() {
            csv.write_record([
                k.to_string(),
                s.level.to_string(),
                i.to_string(),
                (perturb_seed + i as u64).to_string(),
                i.to_string(),
                a.map(|v| v.to_string()).unwrap_or_default(),
                a.is_none().to_string(),
            ])?;
        }
    }
    Ok(csv.into_inner()?)
}

/// Writes `match.json` (the request and `result`, pretty-printed) and `match.csv` into `out`.
pub fn write_files(
    out: &Path,
    json: &serde_json::Value,
    result: &MatchResult,
    perturb_seed: u64,
) -> Result<()> {
    write_atomic(
        &out.join("match.json"),
        serde_json::to_string_pretty(json)?.as_bytes(),
    )?;
    write_atomic(&out.join("match.csv"), &runs_csv(result, perturb_seed)?)?;
    Ok(())
}

/// The line a match ends with: the level found (and whether it is within `tolerance` of the
/// target); an error when the target lies outside what levels 0 to `high` reach.
pub fn verdict(
    label: &str,
    subject: Subject,
    target: f64,
    high: f64,
    tolerance: f64,
    result: &MatchResult,
) -> Result<String> {
    match result.status {
        MatchStatus::Matched {
            level,
            median,
            within_tolerance,
        } => Ok(format!(
            "{label}: {subject}:{level} gives the baseline a median ATE of {} (target {}{}) after {} levels",
            mm(median),
            mm(target),
            if within_tolerance {
                String::new()
            } else {
                format!(", not within {} %: the closest level measured", tolerance * 100.0)
            },
            result.steps.len()
        )),
        MatchStatus::BelowRange { at_low, at_high } => bail!(
            "{label}: the target {} lies below what {subject} reaches: median ATE {} at level 0, {} at {high} (the twin is already harder)",
            mm(target),
            mm(at_low),
            mm(at_high)
        ),
        MatchStatus::AboveRange { at_low, at_high } => bail!(
            "{label}: the target {} lies above what {subject} reaches: median ATE {} at level 0, {} at {high} (raise --max-level, or the chain cannot make it that hard)",
            mm(target),
            mm(at_low),
            mm(at_high)
        ),
    }
}

/// An ATE in millimetres, or "failed" for an infinite median.
pub fn mm(m: f64) -> String {
    if m.is_finite() {
        format!("{:.1} mm", m * 1e3)
    } else {
        "failed (more than half the runs)".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_and_chains_are_read() {
        assert_eq!(parse_metres("0.023").unwrap(), 0.023);
        assert!((parse_metres("23mm").unwrap() - 0.023).abs() < 1e-15);
        assert_eq!(parse_metres("0.5m").unwrap(), 0.5);
        assert!(parse_metres("-1").is_err() && parse_metres("abc").is_err());
        assert_eq!(chain_of("fr1_desk"), Some(NamedChain::KinectFr1));
        assert_eq!(chain_of("fr3_w_rpy"), Some(NamedChain::KinectFr3));
        assert_eq!(chain_of("mh01"), Some(NamedChain::Euroc));
        assert_eq!(chain_of("kinect"), None);
    }
}
