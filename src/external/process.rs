//! Running an external program as one run of a sweep: its own process group, stdout and
//! stderr into files, a timeout that kills the whole group, and what `wait4` says of it (exit
//! status, peak resident memory, CPU time).

use anyhow::{bail, Context, Result};
use std::collections::BTreeMap;
use std::fs::File;
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How the program ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exit {
    /// It exited with this status.
    Code(i32),
    /// A signal ended it (e.g. 11 for a segmentation fault).
    Signal(i32),
    /// It ran past the timeout and was killed.
    Timeout,
}

/// What a finished program cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Finished {
    /// How it ended.
    pub exit: Exit,
    /// Wall time, seconds.
    pub wall_s: f64,
    /// User + system CPU time, seconds (every thread, and the children it waited for).
    pub cpu_s: f64,
    /// Peak resident set size, bytes.
    pub peak_rss_bytes: u64,
}

impl Finished {
    /// Why the run failed, `None` when the program exited with status 0.
    pub fn failure(&self, timeout: Duration) -> Option<String> {
        match self.exit {
            Exit::Code(0) => None,
            Exit::Code(c) => Some(format!("exit status {c}")),
            Exit::Signal(s) => Some(format!("killed by signal {s}{}", signal_name(s))),
            Exit::Timeout => Some(format!("timeout after {} s", timeout.as_secs_f64())),
        }
    }
}

fn signal_name(s: i32) -> &'static str {
    match s {
        libc::SIGSEGV => " (segmentation fault)",
        libc::SIGABRT => " (abort)",
        libc::SIGKILL => " (killed)",
        libc::SIGBUS => " (bus error)",
        libc::SIGFPE => " (floating-point exception)",
        libc::SIGILL => " (illegal instruction)",
        _ => "",
    }
}

/// Runs `argv` in `workdir` with `env` added, stdout and stderr written to the given files,
/// and waits for it, killing its process group after `timeout`.
pub fn run(
    argv: &[String],
    workdir: &Path,
    env: &BTreeMap<String, String>,
    stdout: &Path,
    stderr: &Path,
    timeout: Duration,
) -> Result<Finished> {
    let Some((program, args)) = argv.split_first() else {
        bail!("empty command");
    };
    let out = File::create(stdout).with_context(|| format!("creating {}", stdout.display()))?;
    let err = File::create(stderr).with_context(|| format!("creating {}", stderr.display()))?;
    let start = Instant::now();
    let child = Command::new(program)
        .args(args)
        .current_dir(workdir)
        .envs(env)
        .stdin(Stdio::null())
        .stdout(out)
        .stderr(err)
        // Its own process group, so a timeout kills what it started too.
        .process_group(0)
        .spawn()
        .with_context(|| format!("starting {program:?} in {}", workdir.display()))?;
    let pid = child.id() as libc::pid_t;
    // The child is reaped by wait4 below (which also gives its resource usage), not by `Child`.
    drop(child);
    let mut status: libc::c_int = 0;
    // SAFETY: rusage is plain old data; wait4 fills it.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let mut timed_out = false;
    let mut pause = Duration::from_millis(2);
    loop {
        let flags = if timed_out { 0 } else { libc::WNOHANG };
        // SAFETY: pid is our child; status and usage are valid for writes.
        let r = unsafe { libc::wait4(pid, &mut status, flags, &mut usage) };
        if r == pid {
            break;
        }
        if r < 0 {
            let e = std::io::Error::last_os_error();
            if e.kind() == std::io::ErrorKind::Interrupted {
                continue;
            }
            return Err(e).context("waiting for the external program");
        }
        if !timed_out && start.elapsed() >= timeout {
            // SAFETY: signalling our child's process group.
            unsafe {
                libc::kill(-pid, libc::SIGKILL);
            }
            timed_out = true;
            continue;
        }
        std::thread::sleep(pause);
        pause = (pause * 2).min(Duration::from_millis(50));
    }
    let wall_s = start.elapsed().as_secs_f64();
    let exit = if timed_out {
        Exit::Timeout
    } else if libc::WIFEXITED(status) {
        Exit::Code(libc::WEXITSTATUS(status))
    } else if libc::WIFSIGNALED(status) {
        Exit::Signal(libc::WTERMSIG(status))
    } else {
        Exit::Code(-1)
    };
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    Ok(Finished {
        exit,
        wall_s,
        cpu_s: secs(usage.ru_utime) + secs(usage.ru_stime),
        // Linux reports ru_maxrss in kilobytes.
        peak_rss_bytes: (usage.ru_maxrss.max(0) as u64) * 1024,
    })
}

/// The last `n` lines of a text file (lossy UTF-8), empty when it cannot be read.
pub fn tail(path: &Path, n: usize) -> String {
    let bytes = std::fs::read(path).unwrap_or_default();
    let text = String::from_utf8_lossy(&bytes);
    let lines: Vec<&str> = text.lines().collect();
    lines[lines.len().saturating_sub(n)..].join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sh(script: &str, timeout_ms: u64) -> (Finished, String) {
        let dir = std::env::temp_dir().join(format!(
            "nf-process-{}-{}",
            std::process::id(),
            script.len()
        ));
        std::fs::create_dir_all(&dir).unwrap();
        let f = run(
            &["sh".into(), "-c".into(), script.into()],
            &dir,
            &BTreeMap::from([("NF_TEST".to_string(), "hello".to_string())]),
            &dir.join("out"),
            &dir.join("err"),
            Duration::from_millis(timeout_ms),
        )
        .unwrap();
        (f, tail(&dir.join("err"), 2))
    }

    #[test]
    fn exit_status_signal_timeout_and_streams() {
        let (f, err) = sh(
            "echo one >&2; echo two >&2; echo $NF_TEST >&2; exit 3",
            5000,
        );
        assert_eq!(f.exit, Exit::Code(3));
        assert_eq!(err, "two\nhello");
        assert_eq!(f.failure(Duration::ZERO).unwrap(), "exit status 3");
        let (f, _) = sh("kill -SEGV $$", 5000);
        assert_eq!(f.exit, Exit::Signal(libc::SIGSEGV));
        assert!(f.failure(Duration::ZERO).unwrap().contains("segmentation"));
        // The sleeping grandchild goes with its group: the call returns at the timeout.
        let (f, _) = sh("sleep 30 & sleep 30", 300);
        assert_eq!(f.exit, Exit::Timeout);
        assert!(f.wall_s < 10.0, "{}", f.wall_s);
        let (f, _) = sh("exit 0", 5000);
        assert_eq!(f.failure(Duration::ZERO), None);
        assert!(f.peak_rss_bytes > 0);
    }

    #[test]
    fn a_program_that_does_not_exist_is_an_error() {
        let e = run(
            &["/nonexistent/slam".into()],
            &std::env::temp_dir(),
            &BTreeMap::new(),
            &std::env::temp_dir().join(format!("nf-p-{}-o", std::process::id())),
            &std::env::temp_dir().join(format!("nf-p-{}-e", std::process::id())),
            Duration::from_secs(1),
        )
        .unwrap_err();
        assert!(format!("{e:#}").contains("/nonexistent/slam"));
    }
}
