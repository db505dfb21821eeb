//! The ablation of a named camera chain (`sweep --ablate kinect-fr1:1`) as one table per chain:
//! for each sequence and system the unperturbed point, the whole chain, each member alone and
//! the chain without each member, with n, mean ± std, median and the 95 % interval of the mean
//! (Student's t over the runs that did not fail). Beside each row, the share of the chain's
//! effect it carries (a member alone: its own effect over the chain's; the chain without a
//! member: what leaving the member out takes away); for a twin, the gap the chain closes
//! towards the paper's ORB-SLAM2 figure of the sequence it imitates.
//!
//! Shares are ratios of mean differences, given without an interval: read them beside the
//! rows' intervals (a share whose rows' intervals overlap says little).

use crate::report::markdown::Rendered;
use crate::report::resilience::{Curve, LevelStats};
use crate::report::stats::mean_ci95;
use perturb::{NamedChain, Subject};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// A level as a table prints it: at most three decimals (the CSV keeps every digit).
fn short(level: f64) -> String {
    format!("{}", (level * 1000.0).round() / 1000.0)
}

/// One row of an ablation table: what was applied and the runs at it.
struct Row<'a> {
    what: String,
    stats: &'a LevelStats,
    share: Option<f64>,
}

/// The stats of `curves[name]` for (`sequence`, `system`) at its non-zero level.
fn perturbed<'a>(
    curves: &'a BTreeMap<String, Vec<Curve>>,
    name: &str,
    sequence: &str,
    system: &str,
) -> Option<&'a LevelStats> {
    curves
        .get(name)?
        .iter()
        .find(|c| c.sequence == sequence && c.system == system)?
        .levels
        .iter()
        .find(|l| l.level != 0.0)
}

/// The ablation tables of a folder's curves, one per named chain that has a curve; `paper`
/// gives a sequence's paper ORB-SLAM2 figure (metres) and the name of the row it imitates.
pub fn tables(
    curves: &BTreeMap<String, Vec<Curve>>,
    paper: impl Fn(&str) -> Option<(String, f64)>,
) -> Vec<(NamedChain, Rendered)> {
    let mut out = Vec::new();
    for chain in NamedChain::ALL {
        let Some(list) = curves.get(chain.name()) else {
            continue;
        };
        // Only a folder with the member rows is an ablation (a chain axis alone is a curve).
        let members = chain.members();
        if !members
            .iter()
            .any(|m| curves.contains_key(&Subject::Without(chain, m.family).name()))
        {
            continue;
        }
        let mut md = format!("## Ablation of {chain}: {}\n", chain.camera());
        let mut csv = String::from(
            "sequence,system,row,applied,n,failed,mean_m,std_m,median_m,ci95_low_m,ci95_high_m,share_of_chain_effect\n",
        );
        for curve in list {
            let Some(zero) = curve.levels.iter().find(|l| l.level == 0.0) else {
                continue;
            };
            let Some(all) = curve.levels.iter().find(|l| l.level != 0.0) else {
                continue;
            };
            let base = mean_ci95(&zero.ates).map(|m| m.0);
            let full = mean_ci95(&all.ates).map(|m| m.0);
            let effect = base.zip(full).map(|(b, f)| f - b);
            let share = |s: &LevelStats, without: bool| -> Option<f64> {
                let m = mean_ci95(&s.ates)?.0;
                let (b, f, e) = (base?, full?, effect?);
                if e.abs() < 1e-12 {
                    return None;
                }
                Some(if without { (f - m) / e } else { (m - b) / e })
            };
            let mut rows = vec![
                Row {
                    what: "none".into(),
                    stats: zero,
                    share: None,
                },
                Row {
                    what: format!("{chain}:{} (every member)", short(all.level)),
                    stats: all,
                    share: None,
                },
            ];
            for p in chain.at(all.level) {
                if let Some(s) = perturbed(curves, p.family.name(), &curve.sequence, &curve.system)
                {
                    rows.push(Row {
                        what: format!("{}:{} alone", p.family, short(p.level)),
                        stats: s,
                        share: share(s, false),
                    });
                }
            }
            for m in members {
                let name = Subject::Without(chain, m.family).name();
                if let Some(s) = perturbed(curves, &name, &curve.sequence, &curve.system) {
                    rows.push(Row {
                        what: format!("without {}", m.family),
                        stats: s,
                        share: share(s, true),
                    });
                }
            }
            let _ = writeln!(md, "\n### {} — {}\n", curve.sequence, curve.label);
            if let (Some((row, p)), Some(b), Some(f)) = (paper(&curve.sequence), base, full) {
                let _ = writeln!(
                    md,
                    "The paper's ORB-SLAM2 on {row}: {:.1} mm. Unperturbed {:.2} mm, under the whole chain {:.2} mm: the chain closes {:.0} % of the gap (mean over the runs).\n",
                    p * 1e3,
                    b * 1e3,
                    f * 1e3,
                    100.0 * (f - b) / (p - b)
                );
            }
            md.push_str("| applied | n (failed) | mean ± std | median | 95 % interval of the mean | share of the chain's effect |\n|---|---|---|---|---|---|\n");
            for r in &rows {
                let ci = mean_ci95(&r.stats.ates);
                let (m, s, med) = (r.stats.mean(), r.stats.std(), r.stats.median());
                let cell =
                    |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{:.2}", v * 1e3));
                let interval = match ci {
                    Some((m, Some(h))) => format!("{:.2} to {:.2}", (m - h) * 1e3, (m + h) * 1e3),
                    _ => "-".into(),
                };
                let _ = writeln!(
                    md,
                    "| {} | {} ({}) | {} ± {} | {} | {} | {} |",
                    r.what,
                    r.stats.n,
                    r.stats.failed,
                    cell(m),
                    cell(s),
                    cell(med),
                    interval,
                    r.share
                        .map_or("-".to_string(), |v| format!("{:.0} %", 100.0 * v))
                );
                let num = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v}"));
                let (lo, hi) = match ci {
                    Some((m, Some(h))) => (Some(m - h), Some(m + h)),
                    _ => (None, None),
                };
                let _ = writeln!(
                    csv,
                    "{},{},{},{},{},{},{},{},{},{},{},{}",
                    curve.sequence,
                    curve.system,
                    r.what.replace(',', ";"),
                    r.stats.level,
                    r.stats.n,
                    r.stats.failed,
                    num(m),
                    num(s),
                    num(med),
                    num(lo),
                    num(hi),
                    num(r.share)
                );
            }
        }
        md.push_str(
            "\nATE RMSE in millimetres over the runs that did not fail; run i of every row sees \
             perturbation draw i (unless the sweep ran with --perturb-shared). The interval is the \
             mean's, Student's t at 95 % (sample standard deviation; the ± column is the \
             population one, as every table here). Share of the chain's effect: a member alone, \
             (its mean - unperturbed) / (chain - unperturbed); without a member, (chain - that \
             row) / (chain - unperturbed). Ratios of means, no interval: shares of effects whose \
             intervals overlap say little, and members need not add up (they interact).\n",
        );
        out.push((chain, Rendered { markdown: md, csv }));
    }
    out
}
