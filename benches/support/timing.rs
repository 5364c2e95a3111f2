//! Timing for the report and scaling examples: medians of repeated runs, CPU and wall clock.

#![allow(
    dead_code,
    reason = "shared by the examples and the bench; each uses a part"
)]

use std::time::Instant;

/// The median of `v` (the mean of the middle two for an even count); NaN when empty.
pub fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// CPU time consumed by the calling thread so far (seconds), from
/// `/proc/thread-self/schedstat`; `None` where that file does not exist.
pub fn thread_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// CPU time consumed by the whole process so far (seconds, all threads), from the `utime`
/// and `stime` fields of `/proc/self/stat` (in units of 1/100 s, Linux's `USER_HZ`).
pub fn process_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &text[text.rfind(')')? + 1..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = fields.get(11)?.parse().ok()?;
    let stime: f64 = fields.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

/// Seconds per call, medians over runs.
#[derive(Clone, Copy, Debug)]
pub struct Timing {
    /// CPU time of the calling thread per call: what the work costs, without the time spent
    /// waiting for a core on a shared machine (the wall-clock time where the thread's CPU
    /// time cannot be read).
    pub cpu: f64,
    /// Wall-clock time per call.
    pub wall: f64,
}

/// Times `f` on the calling thread: one warm-up call, then `runs` timed runs, each of as many
/// calls as make it last at least `min_run` seconds (calibrated on the warm-up); the medians
/// over runs of the thread's CPU time and of the wall-clock time per call.
pub fn time_per_call(runs: usize, min_run: f64, mut f: impl FnMut()) -> Timing {
    let t0 = Instant::now();
    f();
    let once = t0.elapsed().as_secs_f64().max(1e-9);
    let reps = ((min_run / once).ceil() as usize).max(1);
    let (mut cpu, mut wall) = (Vec::new(), Vec::new());
    for _ in 0..runs.max(1) {
        let c = thread_cpu_seconds();
        let t = Instant::now();
        for _ in 0..reps {
            f();
        }
        let w = t.elapsed().as_secs_f64() / reps as f64;
        wall.push(w);
        cpu.push(match (c, thread_cpu_seconds()) {
            (Some(a), Some(b)) => (b - a) / reps as f64,
            _ => w,
        });
    }
    Timing {
        cpu: median(&mut cpu),
        wall: median(&mut wall),
    }
}

/// A duration in seconds with a unit that keeps 3 significant digits (ns, µs, ms or s).
pub fn fmt_seconds(s: f64) -> String {
    if !s.is_finite() {
        return "—".to_string();
    }
    let (v, unit) = if s < 1e-6 {
        (s * 1e9, "ns")
    } else if s < 1e-3 {
        (s * 1e6, "µs")
    } else if s < 1.0 {
        (s * 1e3, "ms")
    } else {
        (s, "s")
    };
    let digits = if v >= 100.0 {
        0
    } else if v >= 10.0 {
        1
    } else {
        2
    };
    format!("{v:.digits$} {unit}")
}

/// The 1-minute load average, as text (for report headers).
pub fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|t| t.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "unknown".to_string())
}

/// The CPU model name, as text (for report headers).
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|s| s.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".to_string())
}
