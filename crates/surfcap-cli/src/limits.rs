//! Refusing requests whose output or working memory would exceed what the machine has, before
//! any work. A few characters of arguments (`--steps 100000`, a key at frame 100000, `--time
//! 1e9`, a 2 km curve) ask for hours of search and gigabytes to terabytes of memory; the frame
//! count is estimated from the request, the bytes from frames x vertices (and the timed search's
//! tables), and the request is refused with the size, the limit and the option that raises it
//! (`surfcap_synthesis::request_size`). Here: the options, and the memory available, read from
//! the environment (Linux's `/proc/meminfo`), which a library does not read.

use std::str::FromStr;

use surfcap_synthesis::request_size::SizeLimits;
pub use surfcap_synthesis::request_size::{DEFAULT_MAX_FRAMES, Request};

/// Bounds on what one request may produce.
#[derive(clap::Args, Debug, Clone)]
pub struct LimitOpts {
    /// Most frames the animation may have (estimated from the request before any work); raise it
    /// for longer animations.
    #[arg(long, default_value_t = DEFAULT_MAX_FRAMES)]
    pub max_frames: usize,
}

impl Default for LimitOpts {
    fn default() -> Self {
        LimitOpts { max_frames: DEFAULT_MAX_FRAMES }
    }
}

/// A byte count: `123`, `512M`, `1.5G` (`--max-memory`, `--max-disk`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bytes(pub u64);

impl FromStr for Bytes {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim();
        let (num, unit) = t.split_at(t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len()));
        let scale = match unit.to_ascii_uppercase().trim_end_matches("IB").trim_end_matches('B') {
            "" => 1u64,
            "K" => 1 << 10,
            "M" => 1 << 20,
            "G" => 1 << 30,
            "T" => 1 << 40,
            _ => return Err(format!("{s:?}: expected a number of bytes, e.g. 800M or 16G")),
        };
        match num.trim().parse::<f64>() {
            Ok(x) if x.is_finite() && x > 0.0 => Ok(Bytes((x * scale as f64) as u64)),
            _ => Err(format!("{s:?}: expected a positive number of bytes, e.g. 800M or 16G")),
        }
    }
}

/// Memory available to new allocations (Linux `MemAvailable`), in bytes.
pub fn mem_available() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = s.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Free space (for an unprivileged user) on the file system that holds `path`, or its nearest
/// existing ancestor, in bytes; `None` when it cannot be found.
pub fn free_disk(path: &std::path::Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let abs = std::path::absolute(path).ok()?;
    let existing = abs.ancestors().find(|p| p.exists())?;
    let c = std::ffi::CString::new(existing.as_os_str().as_bytes()).ok()?;
    let mut st: libc::statvfs = unsafe { std::mem::zeroed() };
    // SAFETY: `c` is a NUL-terminated path and `st` a writable statvfs.
    if unsafe { libc::statvfs(c.as_ptr(), &mut st) } != 0 {
        return None;
    }
    Some((st.f_bavail as u64).saturating_mul(st.f_frsize as u64))
}

impl LimitOpts {
    /// The limits of `--max-frames` and the global `--max-memory` and `--max-disk`, with the
    /// memory available now and the free space where `output` goes.
    pub fn limits(&self, ctx: &crate::Ctx, output: &std::path::Path) -> SizeLimits {
        SizeLimits {
            max_frames: self.max_frames,
            max_memory: ctx.max_memory,
            available_memory: mem_available(),
            max_disk: ctx.max_disk,
            free_disk: free_disk(output),
        }
    }

    /// Refuses `r`, written to `output`, when it exceeds the limits (`SizeLimits::check`).
    pub fn check(&self, ctx: &crate::Ctx, output: &std::path::Path, r: &Request) -> anyhow::Result<()> {
        Ok(self.limits(ctx, output).check(r)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_synthesis::request_size::human;

    #[test]
    fn byte_counts_parse_with_binary_suffixes_and_bad_ones_are_refused() {
        assert_eq!("800".parse(), Ok(Bytes(800)));
        assert_eq!("1.5K".parse(), Ok(Bytes(1536)));
        assert_eq!("2GiB".parse(), Ok(Bytes(2 << 30)));
        assert_eq!("16g".parse(), Ok(Bytes(16 << 30)));
        for bad in ["", "-1G", "0", "12X", "nanG"] {
            assert!(bad.parse::<Bytes>().is_err(), "{bad:?}");
        }
        assert_eq!(human(1536), "1.5 KiB");
        assert_eq!(human(12), "12 bytes");
    }
}
