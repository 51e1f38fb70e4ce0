//! What the benchmarks measure besides the wall time, on Linux: the peak resident memory, the
//! CPU time, the load average (the machine is shared); and the verdict against a target.

use surfcap_mesh::{NoProgress, Subject};

/// Peak resident set size of this process (Linux `VmHWM`), in bytes.
pub fn peak_rss() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// CPU time of this process so far (user + system, every thread), seconds. On a shared machine
/// the wall time of a run includes the time other processes held the cores; the CPU time is
/// the work itself (and it leaves out waits for the disk).
pub fn cpu_seconds() -> f64 {
    // SAFETY: getrusage fills the zeroed struct it is given; RUSAGE_SELF is always valid.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } != 0 {
        return f64::NAN;
    }
    let t = |v: libc::timeval| v.tv_sec as f64 + v.tv_usec as f64 * 1e-6;
    t(u.ru_utime) + t(u.ru_stime)
}

/// The 1-minute load average (Linux `/proc/loadavg`), to judge how shared the machine was.
pub fn load_average() -> Option<f64> {
    std::fs::read_to_string("/proc/loadavg").ok()?.split_whitespace().next()?.parse().ok()
}

/// "met" when `secs` is under the `target`, else "NOT met".
pub fn verdict(secs: f64, target: f64) -> &'static str {
    if secs < target { "met" } else { "NOT met" }
}

/// The frame rate of a benchmark's subject, when its sources do not give one.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct FpsOpt {
    /// Frame rate for sources that do not give one.
    #[arg(long, value_parser = crate::options::positive)]
    pub fps: Option<f64>,
}

impl FpsOpt {
    /// Opens a benchmark's subject without progress output (the timings are printed instead).
    pub fn open_quietly(&self, path: &std::path::Path) -> anyhow::Result<Subject> {
        let opts = surfcap_formats::import::ImportOptions { fps: self.fps, ..Default::default() };
        Ok(surfcap_formats::import::open_subject(path, &opts, &NoProgress)?.subject)
    }
}
