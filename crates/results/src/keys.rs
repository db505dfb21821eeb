//! The keys of a results folder's runs: a run's parameters beyond its configuration, the key
//! that names a run in runs.csv (so a sweep resumes where it stopped and never runs a run twice),
//! its perturbation's part, and the shard of a cluster's job array a run belongs to.

use anyhow::{bail, Context, Result};

/// Parameters of one run beyond its configuration kind. `None` where the kind does not use it.
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
pub struct Params {
    /// MC-OR tau_MF, metres.
    pub tau_mf: Option<f64>,
    /// MC-OR tau_GF, metres.
    pub tau_gf: Option<f64>,
    /// MC-OR tau_MG, metres.
    pub tau_mg: Option<f64>,
    /// AVC baseline b, metres.
    pub baseline: Option<f64>,
}

/// The part of a run's key its perturbation adds (absent in sweeps without one, so their keys
/// are unchanged).
pub fn perturbation_key(chain: &str, seed: u64) -> String {
    format!("|p={chain}|ps={seed}")
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

/// The key of a run from its fields (shared by the sweep's jobs and the CSV records).
pub fn run_key(
    sequence: &str,
    config: &str,
    p: &Params,
    seed: u64,
    synth_seed: Option<u64>,
) -> String {
    format!(
        "{sequence}|{config}|{}|{}|{}|{}|{seed}|{}",
        fmt_opt(p.tau_mf),
        fmt_opt(p.tau_gf),
        fmt_opt(p.tau_mg),
        fmt_opt(p.baseline),
        synth_seed.map(|s| s.to_string()).unwrap_or_default()
    )
}

/// A 1-based slice `index` of `count` of a job list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// 1-based shard number.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// Parses `K/N` with 1 <= K <= N.
    pub fn parse(s: &str) -> Result<Shard> {
        let (k, n) = s
            .split_once('/')
            .with_context(|| format!("--shard {s:?}: expected K/N, e.g. 3/8"))?;
        let index: usize = k
            .trim()
            .parse()
            .with_context(|| format!("--shard {s:?}: K is not a number"))?;
        let count: usize = n
            .trim()
            .parse()
            .with_context(|| format!("--shard {s:?}: N is not a number"))?;
        if count == 0 || index == 0 || index > count {
            bail!("--shard {s:?}: need 1 <= K <= N");
        }
        Ok(Shard { index, count })
    }

    /// The shard of a Slurm job array, from SLURM_ARRAY_TASK_ID, SLURM_ARRAY_TASK_COUNT and
    /// SLURM_ARRAY_TASK_MIN (so `--array=0-7` and `--array=1-8` both work).
    pub fn from_slurm(get: impl Fn(&str) -> Option<String>) -> Result<Option<Shard>> {
        let (Some(id), Some(count)) = (get("SLURM_ARRAY_TASK_ID"), get("SLURM_ARRAY_TASK_COUNT"))
        else {
            return Ok(None);
        };
        let id: usize = id
            .trim()
            .parse()
            .context("SLURM_ARRAY_TASK_ID is not a number")?;
        let count: usize = count
            .trim()
            .parse()
            .context("SLURM_ARRAY_TASK_COUNT is not a number")?;
        let min: usize = match get("SLURM_ARRAY_TASK_MIN") {
            Some(m) => m
                .trim()
                .parse()
                .context("SLURM_ARRAY_TASK_MIN is not a number")?,
            None => 0,
        };
        if id < min || id - min >= count {
            bail!("SLURM_ARRAY_TASK_ID {id} is outside the array (min {min}, count {count}); use a contiguous --array");
        }
        Ok(Some(Shard {
            index: id - min + 1,
            count,
        }))
    }

    /// Whether job number `i` (0-based position in the full list) belongs to this shard.
    /// Round-robin, so every shard gets a similar mix of sequences and configurations.
    pub fn contains(&self, i: usize) -> bool {
        i % self.count == self.index - 1
    }
}
