//! `fuzz`: runs fuzz targets for a chosen time on one thread, with the counting allocator
//! installed, prints what each found and appends it to a tally file.
//!
//! ```text
//! fuzz [--target NAME|all] [--secs N] [--inputs N] [--seed S] [--out DIR] [--tally FILE] [--list]
//! fuzz --target NAME --replay FILE
//! fuzz --summarize TALLY [--seeds S,S...]
//! ```
//! `--summarize` prints the totals of a tally file per target as a Markdown table (inputs,
//! rules broken, the largest peak memory and input), the table of results/fuzz/README.md;
//! with `--seeds`, of the runs from those seeds only.
//! `--replay` reads one saved input with the target's reader and prints the outcome, time and
//! memory, judged by a long run's rules (exit status 1 when it breaks one; a panic is the
//! reader's own, with its backtrace under `RUST_BACKTRACE=1`).
//! `--secs` is per target. Findings (panicking, slow, allocation-bomb inputs) are saved in
//! `--out` (default `target/fuzz`); the exit status is 1 when any target broke a rule.

use fuzz::engine::alloc::Counting;
use fuzz::{Limits, Report};
use std::path::PathBuf;
use std::process::ExitCode;

#[global_allocator]
static ALLOC: Counting = Counting;

struct Args {
    target: String,
    secs: f64,
    inputs: Option<u64>,
    seed: u64,
    out: PathBuf,
    tally: Option<PathBuf>,
    list: bool,
    replay: Option<PathBuf>,
    summarize: Option<PathBuf>,
    seeds: Option<Vec<u64>>,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        target: "all".into(),
        secs: 10.0,
        inputs: None,
        seed: 0,
        out: PathBuf::from("target/fuzz"),
        tally: None,
        list: false,
        replay: None,
        summarize: None,
        seeds: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{flag} needs a value"));
        match flag.as_str() {
            "--target" => a.target = value()?,
            "--secs" => {
                let v = value()?;
                a.secs = v
                    .parse()
                    .ok()
                    .filter(|s: &f64| s.is_finite() && *s >= 0.0)
                    .ok_or_else(|| format!("--secs {v}: must be a number of seconds >= 0"))?;
            }
            "--inputs" => {
                let v = value()?;
                a.inputs = Some(
                    v.parse()
                        .map_err(|_| format!("--inputs {v}: must be a whole number"))?,
                );
            }
            "--seed" => {
                let v = value()?;
                a.seed = v
                    .parse()
                    .map_err(|_| format!("--seed {v}: must be a whole number"))?;
            }
            "--out" => a.out = PathBuf::from(value()?),
            "--tally" => a.tally = Some(PathBuf::from(value()?)),
            "--list" => a.list = true,
            "--replay" => a.replay = Some(PathBuf::from(value()?)),
            "--summarize" => a.summarize = Some(PathBuf::from(value()?)),
            "--seeds" => {
                let v = value()?;
                a.seeds = Some(
                    v.split(',')
                        .map(|s| s.trim().parse())
                        .collect::<Result<_, _>>()
                        .map_err(|_| {
                            format!("--seeds {v}: must be whole numbers, comma-separated")
                        })?,
                );
            }
            "-h" | "--help" => {
                return Err(
                    "usage: fuzz [--target NAME|all] [--secs N] [--inputs N] [--seed S] \
                            [--out DIR] [--tally FILE] [--list] [--replay FILE] \
                            [--summarize TALLY [--seeds S,S...]]"
                        .into(),
                )
            }
            other => return Err(format!("unknown argument {other:?} (see --help)")),
        }
    }
    Ok(a)
}

/// Per-target totals of a tally file as a Markdown table, of the runs from `seeds` only when
/// given; the tally's lines are those `append_tally` writes.
fn summarize(path: &PathBuf, seeds: Option<&[u64]>) -> Result<String, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    // target -> (runs, seconds, inputs, panics, slow, alloc, nameless, peak, largest)
    let mut totals: std::collections::BTreeMap<String, [f64; 9]> = Default::default();
    for (i, line) in text.lines().enumerate().skip(1) {
        let f: Vec<&str> = line.split('\t').collect();
        let num = |k: usize| -> Result<f64, String> {
            f.get(k).and_then(|v| v.parse::<f64>().ok()).ok_or_else(|| {
                format!(
                    "{}:{}: field {} is not a number",
                    path.display(),
                    i + 1,
                    k + 1
                )
            })
        };
        if f.len() != 13 {
            return Err(format!("{}:{}: expected 13 fields", path.display(), i + 1));
        }
        if let Some(seeds) = seeds {
            if !seeds.contains(&(num(1)? as u64)) {
                continue;
            }
        }
        let t = totals.entry(f[0].to_string()).or_insert([0.0; 9]);
        t[0] += 1.0;
        t[1] += num(2)?;
        t[2] += num(3)?;
        for (j, k) in [(3, 6), (4, 7), (5, 8), (6, 9)] {
            t[j] += num(k)?;
        }
        t[7] = t[7].max(num(10)?);
        t[8] = t[8].max(num(11)?);
    }
    let mut out = String::from(
        "| target | runs | wall time | inputs | panics | slow | over allocation | nameless errors | peak memory | largest input |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for (name, t) in &totals {
        out.push_str(&format!(
            "| {name} | {} | {:.0} s | {} | {} | {} | {} | {} | {:.1} MiB | {:.0} KiB |\n",
            t[0],
            t[1],
            t[2],
            t[3],
            t[4],
            t[5],
            t[6],
            t[7] / f64::from(1u32 << 20),
            t[8] / 1024.0
        ));
    }
    Ok(out)
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    if let Some(p) = &args.summarize {
        return match summarize(p, args.seeds.as_deref()) {
            Ok(table) => {
                print!("{table}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("{e}");
                ExitCode::from(2)
            }
        };
    }
    let targets = fuzz::targets::all();
    let status = with_targets(&args, &targets);
    // Every way out of a run, a listing or a replay leaves no scratch folder behind (the
    // targets make theirs, and their seeds', when built).
    fuzz::targets::remove_scratch();
    status
}

/// Lists, replays or runs the targets `args` name.
fn with_targets(args: &Args, targets: &[fuzz::Target]) -> ExitCode {
    if args.list {
        for t in targets {
            println!("{:<20} {}", t.name, t.about);
        }
        return ExitCode::SUCCESS;
    }
    let chosen: Vec<_> = targets
        .iter()
        .filter(|t| args.target == "all" || args.target.split(',').any(|n| n == t.name))
        .collect();
    if chosen.is_empty() {
        eprintln!(
            "no target {:?}; targets: {}",
            args.target,
            targets
                .iter()
                .map(|t| t.name)
                .collect::<Vec<_>>()
                .join(", ")
        );
        return ExitCode::from(2);
    }
    if let Some(file) = &args.replay {
        let input = match std::fs::read(file) {
            Ok(b) => b,
            Err(e) => {
                eprintln!("{}: {e}", file.display());
                return ExitCode::from(2);
            }
        };
        let limits = Limits::long(args.secs, args.out.clone());
        let mut clean = true;
        for t in &chosen {
            let r = fuzz::engine::driver::replay(t, &input, &limits);
            println!("{}", r.summary());
            clean &= r.broken.is_empty();
        }
        return if clean {
            ExitCode::SUCCESS
        } else {
            ExitCode::FAILURE
        };
    }
    let mut limits = Limits::long(args.secs, args.out.clone());
    limits.max_inputs = args.inputs;
    let mut reports = Vec::new();
    for t in chosen {
        let r = fuzz::run(t, args.seed, &limits);
        println!("{}", r.summary());
        if !r.clean() {
            print!("{}", r.details(400));
        }
        // Each target's line as soon as it is done: a later target that ends the process (a
        // hang, an allocation bomb) does not take the earlier ones' records with it.
        if let Some(p) = &args.tally {
            if let Err(e) =
                fuzz::engine::driver::append_tally(p, args.seed, std::slice::from_ref(&r))
            {
                eprintln!("{}: {e}", p.display());
            }
        }
        reports.push(r);
    }
    if reports.iter().all(Report::clean) {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
