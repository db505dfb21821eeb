//! CPU time of the calling thread and of the whole process: what a run or a sweep cost in
//! cores, which wall time cannot say on a machine shared with other work.

/// CPU seconds (user + system) the calling thread has used since it started.
///
/// A run of ours is single-threaded, so the difference of two readings around it is the run's
/// cost on one core, whatever else shares the machine.
pub fn thread_cpu_s() -> f64 {
    clock_s(libc::CLOCK_THREAD_CPUTIME_ID)
}

/// CPU seconds (user + system) every thread of this process has used since it started: a
/// sweep's rendering, reading, extraction and runs together.
pub fn process_cpu_s() -> f64 {
    clock_s(libc::CLOCK_PROCESS_CPUTIME_ID)
}

fn clock_s(clock: libc::clockid_t) -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is valid for writes; both clocks exist on every Linux since 2.6.12.
    let r = unsafe { libc::clock_gettime(clock, &mut t) };
    if r != 0 {
        return 0.0;
    }
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, Instant};

    /// Busy work until the thread's own clock has advanced `seconds` (or 20 s of wall time
    /// passed); returns the CPU and wall seconds it took.
    fn spin_cpu(seconds: f64) -> (f64, f64) {
        let (c0, w0) = (thread_cpu_s(), Instant::now());
        let mut x = 0u64;
        while thread_cpu_s() - c0 < seconds && w0.elapsed().as_secs_f64() < 20.0 {
            for _ in 0..10_000 {
                x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
            }
        }
        (thread_cpu_s() - c0, w0.elapsed().as_secs_f64())
    }

    #[test]
    fn busy_work_counts_and_sleep_does_not() {
        let (cpu, wall) = spin_cpu(0.1);
        assert!(
            cpu >= 0.1,
            "the thread clock did not advance: {cpu} s in {wall} s"
        );
        assert!(
            cpu <= wall + 0.01,
            "one thread used {cpu} CPU-s in {wall} s"
        );
        let t = thread_cpu_s();
        std::thread::sleep(Duration::from_millis(200));
        let asleep = thread_cpu_s() - t;
        assert!(asleep < 0.05, "asleep {asleep}");
    }

    #[test]
    fn the_process_counts_every_thread() {
        let p0 = process_cpu_s();
        let workers: Vec<_> = (0..2)
            .map(|_| std::thread::spawn(|| spin_cpu(0.1).0))
            .collect();
        let threads: f64 = workers.into_iter().map(|w| w.join().unwrap()).sum();
        let used = process_cpu_s() - p0;
        assert!(threads >= 0.2, "{threads}");
        assert!(
            used >= threads,
            "process {used} s, its two threads {threads} s"
        );
    }
}
