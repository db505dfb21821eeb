//! The fuzz loop: draws inputs from a target's [`Mutator`], hands each to the reader under
//! `catch_unwind`, and keeps the books a reader is judged by:
//! - a panic is a crash: counted, its input shrunk to the smallest that still panics, saved;
//! - an input that takes longer than a base time plus a time per byte is slow (a reader must
//!   run in time linear in its input); one that takes longer than the hang limit is stopped by
//!   a watchdog, which saves it and ends the process;
//! - with the counting allocator installed ([`super::alloc`]), an input for which the reader
//!   had more bytes live at once than a floor plus a multiple of the input's size is an
//!   allocation bomb (a header believed), and a single allocation beyond a hard limit is saved
//!   and aborts the process before it takes the machine's memory;
//! - an error that does not name the file (when the reader reads one) is a finding too.
//!
//! One run at a time per process: the state the watchdog and the allocation limit share is
//! global, and [`run`] takes a lock for its duration.

use super::alloc;
use super::mutate::Mutator;
use super::rng::Rng;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A reader under test: takes the bytes of a file, returns whether it accepted them (`Err`
/// holds the error message shown to the user).
pub type Reader = Box<dyn Fn(&[u8]) -> Result<(), String> + Send + Sync>;

/// A fuzz target: one reader, its seeds, and what it is held to.
pub struct Target {
    /// Short name (`tum-trajectory`), used on the command line and in the results.
    pub name: &'static str,
    /// What it reads, for the results table.
    pub about: &'static str,
    /// The file name every error must contain; empty for readers of memory (no file).
    pub file: &'static str,
    /// The input generator over the seeds.
    pub mutator: Mutator,
    /// Applied to every mutated input: repairs a checksum or CRC so that mutations reach the
    /// parser behind it (on 7 inputs of 8; the rest go unrepaired).
    pub fixup: Option<fn(&mut [u8])>,
    /// Bytes the reader may have live beyond the input's size times this (a compressed image
    /// may decode to 1032 times its size, a text line to a few times its length).
    pub alloc_factor: f64,
    /// The reader.
    pub read: Reader,
}

impl Target {
    /// A target without a fixup: `seeds` mutated with the words of `dictionary`, `read` run on
    /// every input, at most `alloc_factor` bytes live per input byte.
    pub fn new(
        name: &'static str,
        about: &'static str,
        file: &'static str,
        seeds: Vec<Vec<u8>>,
        dictionary: &[&str],
        alloc_factor: f64,
        read: Reader,
    ) -> Target {
        Target {
            name,
            about,
            file,
            mutator: Mutator::new(
                seeds,
                dictionary.iter().map(|w| w.as_bytes().to_vec()).collect(),
            ),
            fixup: None,
            alloc_factor,
            read,
        }
    }
}

/// A reader of files: each input is written to `path`, then `read` runs on it.
pub fn on_file(
    path: PathBuf,
    read: impl Fn(&Path) -> Result<(), String> + Send + Sync + 'static,
) -> Reader {
    Box::new(move |bytes: &[u8]| {
        std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
        read(&path)
    })
}

/// Bounds an input is held to, and when to stop.
#[derive(Clone, Debug)]
pub struct Limits {
    /// Stop after this many inputs.
    pub max_inputs: Option<u64>,
    /// Stop after this long.
    pub max_time: Option<Duration>,
    /// Time any input may take, besides `time_per_byte` times its length.
    pub time_base: Duration,
    /// Time per input byte (linear time).
    pub time_per_byte: Duration,
    /// An input running this long is a hang: saved, and the process ends.
    pub hang: Duration,
    /// Bytes any input may make the reader hold, besides `alloc_factor` times its length.
    pub alloc_floor: usize,
    /// Largest single allocation granted at all (see [`alloc::set_limit`]).
    pub alloc_hard_limit: usize,
    /// Where crashing, slow and hanging inputs are saved (`None`: not saved).
    pub out_dir: Option<PathBuf>,
}

impl Limits {
    /// The bounds of a short CI pass of `inputs` inputs: generous times (a loaded machine
    /// must not fail it), the same allocation bound as a long run.
    pub fn ci(inputs: u64) -> Limits {
        Limits {
            max_inputs: Some(inputs),
            max_time: None,
            time_base: Duration::from_secs(2),
            time_per_byte: Duration::from_micros(2),
            hang: Duration::from_secs(120),
            alloc_floor: 8 << 20,
            alloc_hard_limit: 1 << 30,
            out_dir: None,
        }
    }

    /// The bounds of a long run of `secs` seconds, saving findings in `out_dir`.
    pub fn long(secs: f64, out_dir: PathBuf) -> Limits {
        Limits {
            max_inputs: None,
            max_time: Some(Duration::from_secs_f64(secs.max(0.0))),
            time_base: Duration::from_millis(250),
            time_per_byte: Duration::from_micros(1),
            hang: Duration::from_secs(20),
            alloc_floor: 8 << 20,
            alloc_hard_limit: 1 << 30,
            out_dir: Some(out_dir),
        }
    }
}

impl Limits {
    /// The time an input of `len` bytes may take.
    pub fn allowed_time(&self, len: usize) -> Duration {
        self.time_base + self.time_per_byte * len as u32
    }

    /// The bytes `target`'s reader may hold for an input of `len` bytes.
    pub fn allowed_bytes(&self, target: &Target, len: usize) -> f64 {
        self.alloc_floor as f64 + target.alloc_factor * len as f64
    }
}

/// Whether an error of `target`'s reader names the file it read (readers of memory have none).
fn names_its_file(target: &Target, msg: &str) -> bool {
    target.file.is_empty() || msg.contains(target.file)
}

/// The time `input` takes, `took` the first time: an input over `allowed` is timed twice more
/// and judged by its fastest run (a machine shared with other work deschedules the reader
/// now and then).
fn fastest(target: &Target, input: &[u8], took: Duration, allowed: Duration) -> Duration {
    if took <= allowed {
        return took;
    }
    (0..2)
        .map(|_| {
            let t = Instant::now();
            let _ = catch_unwind(AssertUnwindSafe(|| (target.read)(input)));
            t.elapsed()
        })
        .fold(took, Duration::min)
}

/// What one input did when read again by [`replay`].
#[derive(Clone, Debug)]
pub struct Replay {
    /// Target name.
    pub target: String,
    /// Input size, bytes.
    pub len: usize,
    /// The reader's answer.
    pub outcome: Result<(), String>,
    /// The time it took (over the bound: its fastest of three runs).
    pub took: Duration,
    /// Most bytes live at once beyond those live before, when counted.
    pub peak_bytes: Option<u64>,
    /// The rules it broke, as a run judges them (empty: none).
    pub broken: Vec<String>,
}

impl Replay {
    /// The outcome, time, memory and verdict, on a few lines.
    pub fn summary(&self) -> String {
        let peak = self.peak_bytes.map_or("not counted".into(), |b| {
            format!("{:.1} MiB", b as f64 / (1u64 << 20) as f64)
        });
        let verdict = if self.broken.is_empty() {
            "keeps every rule".to_string()
        } else {
            format!("BREAKS: {}", self.broken.join("; "))
        };
        format!(
            "{}: {} bytes read in {:.3} ms, peak {peak}\n  {:?}\n  {verdict}",
            self.target,
            self.len,
            self.took.as_secs_f64() * 1e3,
            self.outcome
        )
    }
}

/// Reads one saved input (a finding of a run, a hand-made file) with `target`'s reader as a
/// run reads it, and judges it by `limits`: time, memory, an error without the file's name. A
/// panic is not caught: it surfaces as the reader's own, with its backtrace under
/// `RUST_BACKTRACE=1`; a single allocation over the hard limit aborts, as in a run.
pub fn replay(target: &Target, input: &[u8], limits: &Limits) -> Replay {
    let _one_at_a_time = lock(&RUN_LOCK);
    alloc::Counting::install_check();
    let counted = alloc::installed();
    if counted {
        alloc::set_limit(limits.alloc_hard_limit, on_alloc_limit);
    }
    let base = alloc::reset_peak();
    let t = Instant::now();
    let outcome = (target.read)(input);
    let took = t.elapsed();
    let peak = (alloc::peak() - base).max(0) as u64;
    if counted {
        alloc::set_limit(usize::MAX, on_alloc_limit);
    }
    let allowed = limits.allowed_time(input.len());
    let took = fastest(target, input, took, allowed);
    let mut broken = Vec::new();
    if took > allowed {
        broken.push(format!(
            "slow: {:.1} ms, allowed {:.1} ms",
            took.as_secs_f64() * 1e3,
            allowed.as_secs_f64() * 1e3
        ));
    }
    let bound = limits.allowed_bytes(target, input.len());
    if counted && peak as f64 > bound {
        broken.push(format!("{peak} bytes live, allowed {bound:.0}"));
    }
    if let Err(msg) = &outcome {
        if !names_its_file(target, msg) {
            broken.push(format!("the error does not name {}", target.file));
        }
    }
    Replay {
        target: target.name.to_string(),
        len: input.len(),
        outcome,
        took,
        peak_bytes: counted.then_some(peak),
        broken,
    }
}

/// One input that broke a rule, shrunk where the rule is a panic.
#[derive(Clone, Debug)]
pub struct Finding {
    /// What happened: the panic message, the time, the bytes.
    pub what: String,
    /// The (smallest found) input.
    pub input: Vec<u8>,
}

/// What a run found.
#[derive(Clone, Debug, Default)]
pub struct Report {
    /// Target name.
    pub target: String,
    /// Inputs tried.
    pub inputs: u64,
    /// Inputs the reader accepted.
    pub accepted: u64,
    /// Inputs it refused with an error.
    pub refused: u64,
    /// Panics (first few kept).
    pub panics: Vec<Finding>,
    /// Number of panicking inputs.
    pub n_panics: u64,
    /// Inputs over the time bound.
    pub slow: Vec<Finding>,
    /// Number of slow inputs.
    pub n_slow: u64,
    /// Inputs over the allocation bound.
    pub alloc: Vec<Finding>,
    /// Number of inputs over the allocation bound.
    pub n_alloc: u64,
    /// Errors that do not name the file.
    pub nameless: Vec<Finding>,
    /// Number of such errors.
    pub n_nameless: u64,
    /// Most bytes live at once for one input (beyond those live before it), when counted.
    pub peak_bytes: u64,
    /// Largest input, bytes.
    pub max_input: u64,
    /// Longest time one input took (for an input over the bound, its fastest of three runs).
    pub slowest: Duration,
    /// Wall time of the run.
    pub elapsed: Duration,
    /// Whether allocation was counted (the counting allocator installed).
    pub counted: bool,
}

impl Report {
    /// Whether the reader kept every rule.
    pub fn clean(&self) -> bool {
        self.n_panics == 0 && self.n_slow == 0 && self.n_alloc == 0 && self.n_nameless == 0
    }

    /// One line: the counts, the peak memory and the speed.
    pub fn summary(&self) -> String {
        format!(
            "{:<20} {:>9} inputs ({:>5.1} % refused) {:>3} panics {:>3} slow {:>3} alloc {:>3} nameless  peak {:>7.1} MiB  largest {:>7.1} KiB  slowest {:>6.1} ms  {:>6.0} inputs/s",
            self.target,
            self.inputs,
            100.0 * self.refused as f64 / self.inputs.max(1) as f64,
            self.n_panics,
            self.n_slow,
            self.n_alloc,
            self.n_nameless,
            self.peak_bytes as f64 / (1u64 << 20) as f64,
            self.max_input as f64 / 1024.0,
            self.slowest.as_secs_f64() * 1e3,
            self.inputs as f64 / self.elapsed.as_secs_f64().max(1e-9),
        )
    }

    /// Every finding, with its input shown escaped (at most `max_bytes` of it).
    pub fn details(&self, max_bytes: usize) -> String {
        let mut s = String::new();
        for (kind, list) in [
            ("panic", &self.panics),
            ("slow", &self.slow),
            ("alloc", &self.alloc),
            ("nameless error", &self.nameless),
        ] {
            for f in list {
                s.push_str(&format!(
                    "{} {kind}: {}\n  input ({} bytes): {}\n",
                    self.target,
                    f.what,
                    f.input.len(),
                    escape(&f.input, max_bytes)
                ));
            }
        }
        s
    }
}

/// Bytes as a Rust byte-string literal body (printable ASCII kept, the rest `\xNN`), cut at
/// `max` bytes.
pub fn escape(bytes: &[u8], max: usize) -> String {
    let mut s: String = bytes[..bytes.len().min(max)]
        .iter()
        .flat_map(|&b| std::ascii::escape_default(b))
        .map(char::from)
        .collect();
    if bytes.len() > max {
        s.push_str(&format!("... ({} more bytes)", bytes.len() - max));
    }
    s
}

/// The state shared with the watchdog and the allocation limit's callback.
struct Current {
    target: String,
    input: Vec<u8>,
    out_dir: Option<PathBuf>,
}

static CURRENT: Mutex<Option<Current>> = Mutex::new(None);
static RUN_LOCK: Mutex<()> = Mutex::new(());
static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Saves the input being read as `<out>/<target>-<kind>.bin` (or prints it when there is no
/// out folder); returns where.
fn save_current(kind: &str) -> String {
    let cur = lock(&CURRENT);
    let Some(c) = cur.as_ref() else {
        return "not saved (a replay: the file given)".into();
    };
    match &c.out_dir {
        Some(dir) => {
            let p = dir.join(format!("{}-{kind}.bin", c.target));
            let _ = std::fs::create_dir_all(dir);
            match std::fs::write(&p, &c.input) {
                Ok(()) => p.display().to_string(),
                Err(e) => format!("(cannot save to {}: {e})", p.display()),
            }
        }
        None => format!("input: {}", escape(&c.input, 2000)),
    }
}

fn on_alloc_limit(size: usize) {
    let at = save_current("alloc-bomb");
    eprintln!("fuzz: a single allocation of {size} bytes was asked for; the input is saved: {at}");
}

fn save(out_dir: &Option<PathBuf>, target: &str, kind: &str, n: u64, input: &[u8]) {
    if let Some(dir) = out_dir {
        let _ = std::fs::create_dir_all(dir);
        let _ = std::fs::write(dir.join(format!("{target}-{kind}-{n}.bin")), input);
    }
}

/// Whether `read` panics on `input` (the message is in [`LAST_PANIC`]).
fn panics(read: &Reader, input: &[u8]) -> bool {
    catch_unwind(AssertUnwindSafe(|| read(input))).is_err()
}

/// The smallest input found that still panics: chunks removed, halving, then single bytes
/// replaced by `0`, within `budget` tries.
pub fn shrink(read: &Reader, input: &[u8], budget: usize) -> Vec<u8> {
    let mut best = input.to_vec();
    let mut tries = 0;
    let mut chunk = best.len().div_ceil(2).max(1);
    loop {
        let mut i = 0;
        while i < best.len() && tries < budget {
            let mut cand = best.clone();
            let end = (i + chunk).min(cand.len());
            cand.drain(i..end);
            tries += 1;
            if panics(read, &cand) {
                best = cand;
            } else {
                i += chunk;
            }
        }
        if chunk == 1 || tries >= budget {
            break;
        }
        chunk = chunk.div_ceil(2);
    }
    best
}

/// Runs `target` from `seed` until `limits` say stop.
pub fn run(target: &Target, seed: u64, limits: &Limits) -> Report {
    let _one_at_a_time = lock(&RUN_LOCK);
    alloc::Counting::install_check();
    let counted = alloc::installed();
    if counted {
        alloc::set_limit(limits.alloc_hard_limit, on_alloc_limit);
    }
    *lock(&CURRENT) = Some(Current {
        target: target.name.to_string(),
        input: Vec::new(),
        out_dir: limits.out_dir.clone(),
    });

    // Panics of this thread are recorded, not printed; others go to the previous hook.
    let me = std::thread::current().id();
    let previous: Arc<dyn Fn(&std::panic::PanicHookInfo<'_>) + Send + Sync> =
        Arc::from(std::panic::take_hook());
    let prev = previous.clone();
    std::panic::set_hook(Box::new(move |info| {
        if std::thread::current().id() == me {
            *lock(&LAST_PANIC) = Some(info.to_string());
        } else {
            prev(info);
        }
    }));

    // The watchdog: an input running past the hang limit is saved and the process ends.
    let started_ms = Arc::new(AtomicU64::new(0));
    let done = Arc::new(AtomicBool::new(false));
    let epoch = Instant::now();
    let watchdog = spawn_watchdog(target.name, limits.hang, &started_ms, &done, epoch);

    let mut rng = Rng::new(seed);
    let mut report = Report {
        target: target.name.to_string(),
        counted,
        ..Report::default()
    };
    let t0 = Instant::now();
    loop {
        if limits.max_inputs.is_some_and(|n| report.inputs >= n)
            || limits.max_time.is_some_and(|t| t0.elapsed() >= t)
        {
            break;
        }
        let mut input = target.mutator.input(&mut rng);
        if let Some(fix) = target.fixup {
            if !rng.one_in(8) {
                fix(&mut input);
            }
        }
        if let Some(c) = lock(&CURRENT).as_mut() {
            c.input.clear();
            c.input.extend_from_slice(&input);
        }
        report.inputs += 1;
        report.max_input = report.max_input.max(input.len() as u64);

        let base = alloc::reset_peak();
        started_ms.store(epoch.elapsed().as_millis().max(1) as u64, Ordering::Relaxed);
        let t = Instant::now();
        let result = catch_unwind(AssertUnwindSafe(|| (target.read)(&input)));
        let took = t.elapsed();
        started_ms.store(0, Ordering::Relaxed);
        let peak = (alloc::peak() - base).max(0) as u64;

        record(
            &mut report,
            target,
            limits,
            counted,
            &input,
            result,
            took,
            peak,
        );
    }
    report.elapsed = t0.elapsed();
    done.store(true, Ordering::Relaxed);
    let _ = watchdog.join();
    let _ = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| previous(info)));
    if counted {
        alloc::set_limit(usize::MAX, on_alloc_limit);
    }
    *lock(&CURRENT) = None;
    report
}

/// Records what one input did: accepted, refused (with or without its file's name), panicked,
/// slow, or over its allocation bound; the findings saved and the first few kept.
#[allow(clippy::too_many_arguments)]
fn record(
    report: &mut Report,
    target: &Target,
    limits: &Limits,
    counted: bool,
    input: &[u8],
    result: std::thread::Result<Result<(), String>>,
    took: Duration,
    peak: u64,
) {
    const KEEP: usize = 3;
    report.peak_bytes = report.peak_bytes.max(peak);
    match result {
        Ok(Ok(())) => report.accepted += 1,
        Ok(Err(msg)) => {
            report.refused += 1;
            if !names_its_file(target, &msg) {
                report.n_nameless += 1;
                if report.nameless.len() < KEEP {
                    report.nameless.push(Finding {
                        what: format!("error without the file name: {msg}"),
                        input: input.to_vec(),
                    });
                }
            }
        }
        Err(_) => {
            report.n_panics += 1;
            let msg = lock(&LAST_PANIC).take().unwrap_or_default();
            save(
                &limits.out_dir,
                target.name,
                "panic",
                report.n_panics,
                input,
            );
            if report.panics.len() < KEEP {
                let small = shrink(&target.read, input, 3000);
                report.panics.push(Finding {
                    what: msg,
                    input: small,
                });
            }
        }
    }
    let allowed = limits.allowed_time(input.len());
    let took = fastest(target, input, took, allowed);
    report.slowest = report.slowest.max(took);
    if took > allowed {
        report.n_slow += 1;
        save(&limits.out_dir, target.name, "slow", report.n_slow, input);
        if report.slow.len() < KEEP {
            report.slow.push(Finding {
                what: format!(
                    "{:.1} ms for {} bytes (allowed {:.1} ms)",
                    took.as_secs_f64() * 1e3,
                    input.len(),
                    allowed.as_secs_f64() * 1e3
                ),
                input: input.to_vec(),
            });
        }
    }
    let bound = limits.allowed_bytes(target, input.len());
    if counted && peak as f64 > bound {
        report.n_alloc += 1;
        save(&limits.out_dir, target.name, "alloc", report.n_alloc, input);
        if report.alloc.len() < KEEP {
            report.alloc.push(Finding {
                what: format!(
                    "{peak} bytes live for a {}-byte input (allowed {bound:.0})",
                    input.len()
                ),
                input: input.to_vec(),
            });
        }
    }
}

/// Starts the thread that ends the process when an input has run past `hang` (`started_ms`:
/// when the current input started, in ms since `epoch`, 0 between inputs), saving the input
/// first; it stops when `done` is set.
fn spawn_watchdog(
    name: &'static str,
    hang: Duration,
    started_ms: &Arc<AtomicU64>,
    done: &Arc<AtomicBool>,
    epoch: Instant,
) -> std::thread::JoinHandle<()> {
    let (started_ms, done) = (started_ms.clone(), done.clone());
    std::thread::spawn(move || {
        while !done.load(Ordering::Relaxed) {
            std::thread::sleep(Duration::from_millis(50));
            let s = started_ms.load(Ordering::Relaxed);
            let now = epoch.elapsed().as_millis() as u64;
            if s > 0 && now.saturating_sub(s) > hang.as_millis() as u64 {
                let at = save_current("hang");
                eprintln!(
                    "fuzz: {name}: an input has run for more than {} s (a hang); saved: {at}",
                    hang.as_secs_f64()
                );
                std::process::exit(70);
            }
        }
    })
}

/// Appends one tab-separated line per report to the tally file `path` (with a header when the
/// file is new): the record of every run, from which the results' totals are summed.
pub fn append_tally(path: &Path, seed: u64, reports: &[Report]) -> std::io::Result<()> {
    use std::io::Write as _;
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

/// A scratch folder for the readers that take a path: under `/dev/shm` when it exists (no
/// disk writes for millions of inputs), else the system's temporary folder; one per process.
pub fn scratch_dir(name: &str) -> PathBuf {
    let shm = Path::new("/dev/shm");
    let base = if shm.is_dir() {
        shm.to_path_buf()
    } else {
        std::env::temp_dir()
    };
    let dir = base.join(format!("noisefree-fuzz-{name}-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    dir
}

#[cfg(test)]
mod tests {
    use super::*;

    fn target(read: Reader) -> Target {
        Target {
            name: "t",
            about: "test",
            file: "f.txt",
            mutator: Mutator::new(vec![b"12 34\n56 78\n".to_vec()], vec![]),
            fixup: None,
            alloc_factor: 4.0,
            read,
        }
    }

    #[test]
    fn panics_are_caught_counted_and_shrunk() {
        let t = target(Box::new(|b: &[u8]| {
            if b.contains(&b'9') {
                panic!("a nine");
            }
            Err("f.txt:1: no".into())
        }));
        let r = run(&t, 1, &Limits::ci(2000));
        assert_eq!(r.inputs, 2000);
        assert!(r.n_panics > 0, "{}", r.summary());
        assert!(r.panics[0].what.contains("a nine"), "{}", r.panics[0].what);
        assert_eq!(r.panics[0].input, b"9");
        assert_eq!(r.n_nameless, 0);
        assert!(!r.clean());
    }

    #[test]
    fn a_replay_judges_one_input_by_the_rules_of_a_run() {
        let t = target(Box::new(|b: &[u8]| {
            if b.starts_with(b"big") {
                let v = vec![1u8; 64 << 20];
                return Err(format!("f.txt: {}", v.len()));
            }
            if b.is_empty() {
                return Err("no name".into());
            }
            Ok(())
        }));
        let limits = Limits::ci(1);
        let ok = replay(&t, b"12 34\n", &limits);
        assert_eq!(ok.outcome, Ok(()));
        assert!(ok.broken.is_empty(), "{}", ok.summary());
        let nameless = replay(&t, b"", &limits);
        assert_eq!(nameless.broken.len(), 1, "{}", nameless.summary());
        assert!(nameless.summary().contains("does not name f.txt"));
        // The counting allocator is installed in the fuzz binary and the CI tests, not in
        // this crate's unit tests: memory is judged only where counted.
        let big = replay(&t, b"big", &limits);
        assert!(big.outcome.is_err());
        assert_eq!(
            big.broken.is_empty(),
            big.peak_bytes.is_none(),
            "{}",
            big.summary()
        );
    }

    #[test]
    fn errors_without_the_file_name_are_findings() {
        let t = target(Box::new(|_: &[u8]| Err("line 1: bad".into())));
        let r = run(&t, 2, &Limits::ci(50));
        assert_eq!((r.n_nameless, r.refused), (50, 50));
    }
}
