//! Expanding a sweep's command line into a deterministic, ordered list of runs, and slicing it
//! into shards for a cluster's job array.

use anyhow::{bail, Context, Result};

pub use crate::columns::{ConfigKind, RunConfig};
pub use results::keys::{perturbation_key, run_key, Params, Shard};

/// One run of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Job {
    /// Sequence label (catalog name or folder name).
    pub sequence: String,
    /// Configuration: ours, or an external system.
    pub config: RunConfig,
    /// Its parameters.
    pub params: Params,
    /// Seed of the run.
    pub seed: u64,
    /// Synthetic sequences: the seed of the sequence realization (scene textures and noise);
    /// `None` for real sequences.
    pub synth_seed: Option<u64>,
    /// The perturbation of the sequence (`sweep --perturb`); `None` in a sweep without one.
    pub perturbation: Option<PerturbPoint>,
}

impl Job {
    /// The identity of a run in `runs.csv`: a re-run with the same key is skipped.
    pub fn key(&self) -> String {
        let mut k = run_key(
            &self.sequence,
            self.config.name(),
            &self.params,
            self.seed,
            self.synth_seed,
        );
        if let Some(p) = &self.perturbation {
            k += &perturbation_key(&p.chain.to_string(), p.seed);
        }
        k
    }
}

/// A job's perturbation as `runs.csv` columns: (perturbation, perturb_family, perturb_level,
/// perturb_seed).
pub type PerturbColumns = (Option<String>, Option<String>, Option<f64>, Option<u64>);

impl Job {
    /// The folder of the job's sequence under `trajectories/` or `external/`: the sequence, and
    /// for a perturbed sweep a subfolder per perturbation (`kinect/depth-axial_2-ps0`).
    pub fn sequence_folder(&self) -> String {
        match &self.perturbation {
            None => self.sequence.clone(),
            Some(p) => {
                let safe = crate::file_name::safe(&p.chain.to_string());
                format!("{}/{safe}-ps{}", self.sequence, p.seed)
            }
        }
    }

    /// The job's perturbation as `runs.csv` columns (all empty without one).
    pub fn perturbation_columns(&self) -> PerturbColumns {
        match &self.perturbation {
            None => (None, None, None, None),
            Some(p) => (
                Some(p.chain.to_string()),
                p.family.clone(),
                p.level,
                Some(p.seed),
            ),
        }
    }
}

/// One point of a sweep's perturbation axes: the chain applied to the sequence, and which axis
/// member it measures.
#[derive(Clone, Debug, PartialEq)]
pub struct PerturbPoint {
    /// The chain actually applied, in its effective form (printed `depth-axial:2`,
    /// `occluders:1+depth-axial:2`, `none`): parsed once where the sweep's flags are read.
    pub chain: perturb::Chain,
    /// The family of the axis this point belongs to; `None` for the unperturbed point (every
    /// axis' level 0, shared by all of them).
    pub family: Option<String>,
    /// The axis level; `None` for the unperturbed point.
    pub level: Option<f64>,
    /// Seed of the perturbation's draws.
    pub seed: u64,
}

/// The points of `--perturb` axes over a fixed `--perturb-with` chain: one per level of each
/// axis (the fixed chain first, then the axis member), points that apply the same chain
/// merged (every axis' level 0 is the one unperturbed point, listed first).
pub fn perturbation_points(
    axes: &[perturb::Axis],
    with: &perturb::Chain,
    seed: u64,
) -> Vec<PerturbPoint> {
    let mut out: Vec<PerturbPoint> = Vec::new();
    let base = with.effective();
    if axes.is_empty() {
        if !with.is_identity() {
            out.push(PerturbPoint {
                chain: base,
                family: None,
                level: None,
                seed,
            });
        }
        return out;
    }
    let mut push = |p: PerturbPoint| {
        if !out
            .iter()
            .any(|q| q.chain.to_string() == p.chain.to_string())
        {
            out.push(p);
        }
    };
    // The unperturbed point first, when any axis has an identity level.
    if axes
        .iter()
        .any(|a| a.levels.iter().any(|&l| a.subject.is_identity(l)))
    {
        push(PerturbPoint {
            chain: base.clone(),
            family: None,
            level: None,
            seed,
        });
    }
    for axis in axes {
        for &level in &axis.levels {
            let mut chain = with.clone();
            chain.0.extend(axis.subject.at(level));
            let canon = chain.effective();
            if canon.to_string() == base.to_string() {
                continue;
            }
            push(PerturbPoint {
                chain: canon,
                family: Some(axis.subject.name()),
                level: Some(level),
                seed,
            });
        }
    }
    out
}

/// Every job of `jobs` once per perturbation point, sequence-major (a sequence's points go
/// together), then point, then the job order. With `per_run`, run k of a point draws its own
/// perturbation (seed + k) instead of all runs sharing one perturbed copy.
pub fn with_perturbations(jobs: Vec<Job>, points: &[PerturbPoint], per_run: bool) -> Vec<Job> {
    if points.is_empty() {
        return jobs;
    }
    let mut sequences: Vec<String> = Vec::new();
    for j in &jobs {
        if !sequences.contains(&j.sequence) {
            sequences.push(j.sequence.clone());
        }
    }
    let mut out = Vec::new();
    for s in &sequences {
        for p in points {
            for j in jobs.iter().filter(|j| &j.sequence == s) {
                let mut p = p.clone();
                if per_run {
                    p.seed += j.seed;
                }
                out.push(Job {
                    perturbation: Some(p),
                    ..j.clone()
                });
            }
        }
    }
    out
}

/// The paper's Table III as twins: for every row (a catalogued real sequence with the paper's
/// figures, in the table's order) the synthetic twin that imitates it, and the rows no twin
/// imitates.
pub fn table3_twins(catalog: &datasets::Catalog) -> (Vec<String>, Vec<String>) {
    let (mut twins, mut missing) = (Vec::new(), Vec::new());
    for row in catalog
        .entries()
        .iter()
        .filter(|e| !e.is_synthetic() && e.paper.is_some())
    {
        match catalog.twin_of(&row.name) {
            Some(t) => twins.push(t.name.clone()),
            None => missing.push(row.name.clone()),
        }
    }
    (twins, missing)
}

/// The grids of a sweep: each list holds the values to try (defaults: the paper's).
#[derive(Clone, Debug, PartialEq)]
pub struct Grids {
    /// tau_MF values.
    pub tau_mf: Vec<f64>,
    /// tau_GF values.
    pub tau_gf: Vec<f64>,
    /// tau_MG values.
    pub tau_mg: Vec<f64>,
    /// AVC baselines.
    pub baseline: Vec<f64>,
}

/// Expands sequences x configurations x grids x seeds into the ordered job list:
/// sequence-major (so a sequence is decoded once and its runs go together), then
/// configuration, parameters, seed (each of `seeds`). External systems take no parameters.
pub fn expand(
    sequences: &[String],
    configs: &[RunConfig],
    grids: &Grids,
    seeds: std::ops::Range<u64>,
) -> Vec<Job> {
    let mut jobs = Vec::new();
    for seq in sequences {
        for config in configs {
            let Some(kind) = config.kind() else {
                for seed in seeds.clone() {
                    jobs.push(Job {
                        sequence: seq.clone(),
                        config: config.clone(),
                        params: Params {
                            tau_mf: None,
                            tau_gf: None,
                            tau_mg: None,
                            baseline: None,
                        },
                        seed,
                        synth_seed: None,
                        perturbation: None,
                    });
                }
                continue;
            };
            let mut params = Vec::new();
            let reading = crate::readings::of(config);
            let own_taus = reading.and_then(|r| r.readings.tau);
            let mcor_grid: Vec<(Option<f64>, Option<f64>, Option<f64>)> =
                if let Some((a, b, c)) = own_taus {
                    vec![(Some(a), Some(b), Some(c))]
                } else if kind.mcor() {
                    let mut v = Vec::new();
                    for &a in &grids.tau_mf {
                        for &b in &grids.tau_gf {
                            for &c in &grids.tau_mg {
                                v.push((Some(a), Some(b), Some(c)));
                            }
                        }
                    }
                    v
                } else {
                    vec![(None, None, None)]
                };
            let takes_baseline = reading.map_or(kind.avc(), |r| r.takes_baseline());
            let avc_grid: Vec<Option<f64>> = if takes_baseline {
                grids.baseline.iter().map(|&b| Some(b)).collect()
            } else {
                vec![None]
            };
            for &(tau_mf, tau_gf, tau_mg) in &mcor_grid {
                for &baseline in &avc_grid {
                    params.push(Params {
                        tau_mf,
                        tau_gf,
                        tau_mg,
                        baseline,
                    });
                }
            }
            for p in params {
                for seed in seeds.clone() {
                    jobs.push(Job {
                        sequence: seq.clone(),
                        config: config.clone(),
                        params: p,
                        seed,
                        synth_seed: None,
                        perturbation: None,
                    });
                }
            }
        }
    }
    jobs
}

/// Parses a list `0.1,0.3,0.5` or a range `start:stop:step` (inclusive of stop, as the paper's
/// `0.01:0.13:0.02` = 0.01, 0.03, ..., 0.13).
pub fn parse_values(s: &str) -> Result<Vec<f64>> {
    let num = |t: &str| -> Result<f64> {
        let v: f64 = t
            .trim()
            .parse()
            .with_context(|| format!("{t:?} is not a number"))?;
        if !v.is_finite() {
            bail!("{t:?} is not finite");
        }
        Ok(v)
    };
    if s.contains(':') {
        let parts: Vec<&str> = s.split(':').collect();
        if parts.len() != 3 {
            bail!("range {s:?}: expected start:stop:step");
        }
        let (a, b, step) = (num(parts[0])?, num(parts[1])?, num(parts[2])?);
        if step <= 0.0 || b < a {
            bail!("range {s:?}: need step > 0 and stop >= start");
        }
        let n = ((b - a) / step + 1e-9).floor() as usize;
        // Round to 12 decimals so 0.01 + 3 * 0.02 prints as 0.07, not 0.06999999999999999.
        Ok((0..=n)
            .map(|k| ((a + k as f64 * step) * 1e12).round() / 1e12)
            .collect())
    } else {
        s.split(',')
            .filter(|t| !t.trim().is_empty())
            .map(num)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_and_lists() {
        assert_eq!(
            parse_values("0.01:0.13:0.02").unwrap(),
            vec![0.01, 0.03, 0.05, 0.07, 0.09, 0.11, 0.13]
        );
        assert_eq!(parse_values("0.1,0.3, 0.5").unwrap(), vec![0.1, 0.3, 0.5]);
        assert!(parse_values("0.1:0.0:0.1").is_err());
        assert!(parse_values("a,b").is_err());
    }

    #[test]
    fn expansion_counts_and_order() {
        let grids = Grids {
            tau_mf: vec![0.1, 0.7],
            tau_gf: vec![0.7],
            tau_mg: vec![0.5],
            baseline: vec![0.05, 0.09],
        };
        let mut configs: Vec<RunConfig> = ConfigKind::ALL.map(RunConfig::Ours).to_vec();
        configs.push(RunConfig::System("orbslam2".into()));
        let jobs = expand(&["a".into(), "b".into()], &configs, &grids, 0..3);
        // per sequence: orb 1 + mcor 2 + avc 2 + mcor+avc 4 = 9 parameter sets, and the
        // external system's one, x 3 seeds
        assert_eq!(jobs.len(), 2 * 10 * 3);
        let external: Vec<&Job> = jobs.iter().filter(|j| j.config.kind().is_none()).collect();
        assert_eq!(external.len(), 2 * 3);
        assert!(external
            .iter()
            .all(|j| j.params.tau_mf.is_none() && j.params.baseline.is_none()));
        assert!(jobs[..27].iter().all(|j| j.sequence == "a"));
        let keys: std::collections::BTreeSet<String> = jobs.iter().map(Job::key).collect();
        assert_eq!(keys.len(), jobs.len(), "keys are unique");
    }

    #[test]
    fn perturbation_points_merge_the_unperturbed_levels_and_multiply_the_jobs() {
        let axes = vec![
            perturb::Axis::parse("depth-axial:0,1,2").unwrap(),
            perturb::Axis::parse("depth-lateral:0,2").unwrap(),
        ];
        let pts = perturbation_points(&axes, &perturb::Chain::default(), 7);
        let chains: Vec<String> = pts.iter().map(|p| p.chain.to_string()).collect();
        assert_eq!(
            chains,
            ["none", "depth-axial:1", "depth-axial:2", "depth-lateral:2"]
        );
        assert_eq!(pts[0].family, None);
        assert_eq!(pts[2].level, Some(2.0));
        let with = perturb::Chain::parse("occluders:1").unwrap();
        let pts = perturbation_points(&axes[..1], &with, 0);
        assert_eq!(pts[0].chain.to_string(), "occluders:1");
        assert_eq!(pts[1].chain.to_string(), "occluders:1+depth-axial:1");
        let grids = Grids {
            tau_mf: vec![0.7],
            tau_gf: vec![0.7],
            tau_mg: vec![0.5],
            baseline: vec![0.09],
        };
        let configs = vec![
            RunConfig::Ours(ConfigKind::Orb),
            RunConfig::Ours(ConfigKind::Avc),
        ];
        let jobs = expand(&["a".into(), "b".into()], &configs, &grids, 0..2);
        let pts = perturbation_points(&axes, &perturb::Chain::default(), 5);
        let all = with_perturbations(jobs.clone(), &pts, false);
        assert_eq!(all.len(), jobs.len() * 4);
        assert!(all[..16].iter().all(|j| j.sequence == "a"));
        let keys: std::collections::BTreeSet<String> = all.iter().map(Job::key).collect();
        assert_eq!(keys.len(), all.len());
        // Without perturbations the keys are those of a sweep before they existed.
        assert_eq!(jobs[0].key(), "a|orb|||||0|");
        let per_run = with_perturbations(jobs, &pts, true);
        assert_eq!(per_run[1].perturbation.as_ref().unwrap().seed, 6);
    }

    #[test]
    fn shards_partition_the_jobs() {
        for n in 1..6 {
            let shards: Vec<Shard> = (1..=n)
                .map(|k| Shard::parse(&format!("{k}/{n}")).unwrap())
                .collect();
            for i in 0..50 {
                assert_eq!(shards.iter().filter(|s| s.contains(i)).count(), 1);
            }
        }
        assert!(
            Shard::parse("0/3").is_err()
                && Shard::parse("4/3").is_err()
                && Shard::parse("x").is_err()
        );
    }

    #[test]
    fn slurm_environment() {
        let env = |pairs: &'static [(&'static str, &'static str)]| {
            move |k: &str| {
                pairs
                    .iter()
                    .find(|(a, _)| *a == k)
                    .map(|(_, v)| v.to_string())
            }
        };
        assert_eq!(Shard::from_slurm(env(&[])).unwrap(), None);
        let s = Shard::from_slurm(env(&[
            ("SLURM_ARRAY_TASK_ID", "0"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ]))
        .unwrap();
        assert_eq!(s, Some(Shard { index: 1, count: 4 }));
        let s = Shard::from_slurm(env(&[
            ("SLURM_ARRAY_TASK_ID", "8"),
            ("SLURM_ARRAY_TASK_COUNT", "8"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
        ]))
        .unwrap();
        assert_eq!(s, Some(Shard { index: 8, count: 8 }));
    }
}
