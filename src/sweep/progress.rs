//! A sweep's progress: the overall bar (runs done of the sweep, elapsed time and an estimate of
//! the time left), the per-phase bars under it, the run budget of `--max-runs`, and what the
//! invocation cost (frames run per CPU-second of the whole process).

use crate::cpu_time::process_cpu_s;
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// The bars and counters every phase of a sweep reports to.
pub struct Progress {
    /// Where the bars are drawn (hidden with `--quiet`).
    pub multi: MultiProgress,
    overall: ProgressBar,
    finished: AtomicUsize,
    started: AtomicUsize,
    /// Frames fed to the runs finished in this invocation.
    frames: AtomicUsize,
    max_runs: usize,
    since: Instant,
    /// The process's CPU seconds when the invocation started.
    cpu_since: f64,
    /// When the invocation started, Unix seconds to the nanosecond (its cost lines'
    /// `invocation`): two invocations a second apart, as a quick resume makes, stay apart.
    pub started_unix: String,
    /// The cost when the previous point ended ([`Progress::point_cost`]).
    last_point: Mutex<Cost>,
    /// Runs of the sweep (this shard) and how many were recorded before this invocation.
    total: usize,
    done_before: usize,
    /// Whether to print a line per step for a log (stderr not a terminal, not quiet).
    log_lines: bool,
}

impl Progress {
    /// Progress over `total` runs of which `done` are already recorded; at most `max_runs`
    /// start in this invocation.
    pub fn new(total: usize, done: usize, max_runs: Option<usize>, quiet: bool) -> Progress {
        let multi = MultiProgress::with_draw_target(if quiet {
            ProgressDrawTarget::hidden()
        } else {
            ProgressDrawTarget::stderr()
        });
        let overall = multi.add(ProgressBar::new(total as u64));
        overall.set_style(
            ProgressStyle::with_template(
                "{prefix:>12} [{bar:40}] {pos}/{len} runs, elapsed {elapsed}, eta {eta}",
            )
            .expect("static template")
            .progress_chars("=> "),
        );
        overall.set_prefix("sweep");
        overall.set_position(done as u64);
        // The estimate of the time left counts this invocation's runs only.
        overall.reset_eta();
        Progress {
            multi,
            overall,
            finished: AtomicUsize::new(0),
            started: AtomicUsize::new(0),
            frames: AtomicUsize::new(0),
            max_runs: max_runs.unwrap_or(usize::MAX),
            since: Instant::now(),
            cpu_since: process_cpu_s(),
            started_unix: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or_else(
                    |_| "0".into(),
                    |d| format!("{}.{:09}", d.as_secs(), d.subsec_nanos()),
                ),
            last_point: Mutex::new(Cost::default()),
            total,
            done_before: done,
            log_lines: !quiet && !std::io::IsTerminal::is_terminal(&std::io::stderr()),
        }
    }

    /// Where the sweep stands, for a log without bars (stderr redirected to a file): runs
    /// recorded of the total, elapsed time and the time left at this invocation's pace. Nothing
    /// on a terminal (the overall bar shows the same) or with `--quiet`.
    pub fn log_step(&self, what: &str) {
        if !self.log_lines {
            return;
        }
        let finished = self.finished.load(Ordering::SeqCst);
        let elapsed = self.since.elapsed().as_secs_f64();
        let recorded = self.done_before + finished;
        let left = self.total.saturating_sub(recorded);
        let eta = if finished > 0 {
            format!(
                ", about {} left",
                hms(elapsed / finished as f64 * left as f64)
            )
        } else {
            String::new()
        };
        eprintln!(
            "sweep: {what} done; {recorded}/{} runs recorded, {} elapsed{eta}; {}",
            self.total,
            hms(elapsed),
            self.cost().line()
        );
    }

    /// What this invocation has cost so far.
    pub fn cost(&self) -> Cost {
        Cost {
            runs: self.finished.load(Ordering::SeqCst),
            frames: self.frames.load(Ordering::SeqCst),
            cpu_s: process_cpu_s() - self.cpu_since,
            wall_s: self.since.elapsed().as_secs_f64(),
        }
    }

    /// A bar of `len` items under the overall one, labelled `prefix`, counting `what`.
    pub fn bar(&self, len: usize, prefix: String, what: &str) -> ProgressBar {
        let bar = self.multi.add(ProgressBar::new(len as u64));
        bar.set_style(
            ProgressStyle::with_template(&format!(
                "{{prefix:>16}} [{{bar:40}}] {{pos}}/{{len}} {what}"
            ))
            .expect("static template")
            .progress_chars("=> "),
        );
        bar.set_prefix(prefix);
        bar
    }

    /// Whether another run may start (`--max-runs`); a slot is reserved first, so parallel
    /// runs never overshoot the budget.
    pub fn reserve(&self) -> bool {
        self.started.fetch_add(1, Ordering::SeqCst) < self.max_runs
    }

    /// Whether the budget of runs is spent.
    pub fn exhausted(&self) -> bool {
        self.started.load(Ordering::SeqCst) >= self.max_runs
    }

    /// What the invocation has cost since the previous call (or its start): the cost of the
    /// point that just ended, when called once at the end of each.
    pub fn point_cost(&self) -> Cost {
        let now = self.cost();
        let mut last = self.last_point.lock().unwrap_or_else(|e| e.into_inner());
        let d = Cost {
            runs: now.runs - last.runs,
            frames: now.frames - last.frames,
            cpu_s: now.cpu_s - last.cpu_s,
            wall_s: now.wall_s - last.wall_s,
        };
        *last = now;
        d
    }

    /// Counts one finished (recorded) run that was fed `frames` frames.
    pub fn done(&self, frames: usize) {
        self.finished.fetch_add(1, Ordering::SeqCst);
        self.frames.fetch_add(frames, Ordering::SeqCst);
        self.overall.inc(1);
    }

    /// A line printed above the bars (also when stderr is not a terminal).
    pub fn note(&self, line: &str) {
        self.multi.suspend(|| eprintln!("{line}"));
    }

    /// Clears the bars; returns what the invocation cost (its runs finished among it).
    pub fn finish(&self) -> Cost {
        self.overall.finish_and_clear();
        self.cost()
    }
}

/// What an invocation of a sweep cost: the frames its runs were fed, and the CPU time of the
/// whole process (rendering, reading, extraction, the runs and external systems' waiting
/// threads) and the wall time it took. External systems' own processes are not counted (their
/// records carry their CPU time).
#[derive(Clone, Copy, Debug, Default)]
pub struct Cost {
    /// Runs finished.
    pub runs: usize,
    /// Frames fed to them.
    pub frames: usize,
    /// CPU seconds of this process.
    pub cpu_s: f64,
    /// Wall seconds.
    pub wall_s: f64,
}

impl Cost {
    /// Frames run per CPU-second: the sweep's throughput per core, whatever else shares the
    /// machine.
    pub fn frames_per_cpu_s(&self) -> f64 {
        self.frames as f64 / self.cpu_s.max(1e-9)
    }

    /// `12345 frames run in 678 CPU-s (18.2 frames/s per core, 1.9 cores busy)`.
    pub fn line(&self) -> String {
        format!(
            "{} frames run in {:.0} CPU-s ({:.1} frames/s per core, {:.1} cores busy)",
            self.frames,
            self.cpu_s,
            self.frames_per_cpu_s(),
            self.cpu_s / self.wall_s.max(1e-9)
        )
    }
}

pub use results::cost::hms;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_print_in_hours_minutes_and_seconds() {
        assert_eq!(hms(0.4), "0s");
        assert_eq!(hms(59.6), "1m00s");
        assert_eq!(hms(125.0), "2m05s");
        assert_eq!(hms(3723.0), "1h02m03s");
    }
}
