//! `fuzz`: runs fuzz targets for a chosen time on one thread, with the counting allocator
//! installed, prints what each found and appends it to a tally file.
//!
//! ```text
//! fuzz [--target NAME|all] [--secs N] [--inputs N] [--seed S] [--out DIR] [--tally FILE] [--list]
//! fuzz --target NAME --replay FILE
//! ```
//! `--replay` reads one saved input with the target's reader and prints the outcome and time.
//! `--secs` is per target. Findings (panicking, slow, allocation-bomb inputs) are saved in
//! `--out` (default `target/fuzz`); the exit status is 1 when any target broke a rule.

use fuzz::engine::alloc::Counting;
use fuzz::{Limits, Report};
use std::io::Write as _;
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
            "-h" | "--help" => {
                return Err(
                    "usage: fuzz [--target NAME|all] [--secs N] [--inputs N] [--seed S] \
                            [--out DIR] [--tally FILE] [--list] [--replay FILE]"
                        .into(),
                )
            }
            other => return Err(format!("unknown argument {other:?} (see --help)")),
        }
    }
    Ok(a)
}

/// Appends one tab-separated line per report to `path` (header written when the file is new).
fn tally(path: &PathBuf, seed: u64, reports: &[Report]) -> std::io::Result<()> {
    let new = !path.exists();
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)?;
    if new {
        writeln!(
            f,
            "target\tseed\tseconds\tinputs\taccepted\trefused\tpanics\tslow\talloc\tnameless\tpeak_bytes\tlargest_input\tslowest_ms"
        )?;
    }
    for r in reports {
        writeln!(
            f,
            "{}\t{seed}\t{:.1}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{}\t{:.1}",
            r.target,
            r.elapsed.as_secs_f64(),
            r.inputs,
            r.accepted,
            r.refused,
            r.n_panics,
            r.n_slow,
            r.n_alloc,
            r.n_nameless,
            r.peak_bytes,
            r.max_input,
            r.slowest.as_secs_f64() * 1e3
        )?;
    }
    Ok(())
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    let targets = fuzz::targets::all();
    if args.list {
        for t in &targets {
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
        for t in &chosen {
            let t0 = std::time::Instant::now();
            let outcome = (t.read)(&input);
            println!(
                "{}: {:?} in {:.3} ms",
                t.name,
                outcome,
                t0.elapsed().as_secs_f64() * 1e3
            );
        }
        return ExitCode::SUCCESS;
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
        reports.push(r);
    }
    if let Some(p) = &args.tally {
        if let Err(e) = tally(p, args.seed, &reports) {
            eprintln!("{}: {e}", p.display());
        }
    }
    let _ = std::fs::remove_dir_all(fuzz::targets::scratch());
    if reports.iter().all(Report::clean) {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
