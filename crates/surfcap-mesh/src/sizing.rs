//! Sizing a request before any work, and allocating fallibly where a size comes from input.
//!
//! A few characters of arguments (`--frames 1e9`, `--size 16384`, a `model.json` whose width
//! was edited to 1e9) ask for terabytes. Every command that allocates from its arguments or from
//! a file it reads first states an [`Estimate`] (the memory, the disk it will write, and the
//! arguments responsible), and a [`Budget`] (the front end's `--max-memory`, `--max-disk`, the
//! memory available and the free space, which a library does not look up) refuses it with the
//! size, the limit and the option that raises it. Where an estimate cannot be made before
//! reading (the sizes are inside a file), [`try_vec`] and [`try_reserve`] turn an allocation
//! that cannot be met into a [`SizeError`] naming what was being allocated and its size, never
//! an abort. Sizes are computed in `f64` ([`bytes`]), so that a product of huge counts
//! saturates instead of wrapping.
//!
//! The per-command estimates live next to what they size; this module holds only the parts
//! every command shares.

use std::fmt;

/// The limit on memory when neither a limit nor the memory available is known: 4 GiB.
pub const UNKNOWN_MEMORY_LIMIT: u64 = 4 << 30;

/// `12345678` -> `11.8 MiB`.
pub fn human(bytes: u64) -> String {
    let units = ["bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut x = bytes as f64;
    let mut k = 0;
    while x >= 1024.0 && k + 1 < units.len() {
        x /= 1024.0;
        k += 1;
    }
    if k == 0 { format!("{bytes} bytes") } else { format!("{x:.1} {}", units[k]) }
}

/// The bytes of `counts` multiplied together (elements, rows, frames, ...) times `element`
/// bytes, saturating at `u64::MAX` (a NaN or negative count counts as the maximum, so that a
/// nonsense size is refused, never taken as 0).
pub fn bytes(counts: &[f64], element: u64) -> u64 {
    let x = counts.iter().product::<f64>() * element as f64;
    if x.is_nan() || x >= u64::MAX as f64 {
        u64::MAX
    } else if x <= 0.0 {
        // A product of zero counts is zero; a negative one is nonsense.
        if counts.iter().all(|c| *c >= 0.0) { 0 } else { u64::MAX }
    } else {
        x.ceil() as u64
    }
}

/// What a request will take, estimated before any work.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// The arguments responsible, as the user wrote them (`--frames 1000000 at 1024x1024`).
    pub what: String,
    /// Peak memory, bytes.
    pub memory: u64,
    /// Bytes written to disk (0 when nothing is written).
    pub disk: u64,
    /// What to lower instead of raising the limit (`--frames or --size`).
    pub lower: String,
}

/// The limits a request is checked against: the user's and the machine's.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Budget {
    /// Most memory a request may need (`--max-memory`), bytes; default half the memory available.
    pub max_memory: Option<u64>,
    /// The memory available to new allocations when the request starts, if known.
    pub available_memory: Option<u64>,
    /// Most bytes a request may write (`--max-disk`); default the free space, when known.
    pub max_disk: Option<u64>,
    /// Free space on the output's file system, if known.
    pub free_disk: Option<u64>,
}

/// A request refused before any work, or an allocation that could not be met.
#[derive(Debug, Clone, PartialEq)]
pub enum SizeError {
    /// The estimate exceeds a limit.
    Refused {
        /// `{what} needs about 8.0 TiB of disk`, with the limit and how to raise it.
        message: String,
    },
    /// An allocation sized by input could not be met.
    Alloc {
        /// What was being allocated (`the texture of 1000000000 x 3 texels`).
        what: String,
        bytes: u64,
    },
}

impl fmt::Display for SizeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SizeError::Refused { message } => f.write_str(message),
            SizeError::Alloc { what, bytes } => write!(
                f,
                "cannot allocate {what}: {} ({bytes} bytes) is more memory than this machine can give",
                human(*bytes)
            ),
        }
    }
}

impl std::error::Error for SizeError {}

impl From<SizeError> for crate::Error {
    fn from(e: SizeError) -> Self {
        crate::Error::new(crate::ErrorKind::Unsupported, e.to_string())
    }
}

impl Budget {
    /// The memory limit and where it comes from (the option that raises it).
    pub fn memory_limit(&self) -> (u64, String) {
        match (self.max_memory, self.available_memory) {
            (Some(b), _) => (b, "--max-memory; raise it".to_string()),
            (None, Some(a)) => (a / 2, format!("half the {} available; raise it with --max-memory", human(a))),
            (None, None) => (UNKNOWN_MEMORY_LIMIT, "memory available unknown; raise it with --max-memory".to_string()),
        }
    }

    /// Refuses `e` when its memory or its disk exceeds the limits, naming the size, the limit,
    /// the option that raises it and what to lower instead.
    pub fn check(&self, e: &Estimate) -> Result<(), SizeError> {
        let (what, lower) = (&e.what, &e.lower);
        let (limit, whence) = self.memory_limit();
        if e.memory > limit {
            return Err(SizeError::Refused {
                message: format!(
                    "{what} needs about {} of memory, above the limit of {} ({whence} or lower {lower})",
                    human(e.memory),
                    human(limit)
                ),
            });
        }
        if let Some(max) = self.max_disk
            && e.disk > max
        {
            return Err(SizeError::Refused {
                message: format!(
                    "{what} needs about {} of disk, above --max-disk {}; raise --max-disk or lower {lower}",
                    human(e.disk),
                    human(max)
                ),
            });
        }
        if let Some(free) = self.free_disk
            && e.disk > free
        {
            return Err(SizeError::Refused {
                message: format!(
                    "{what} needs about {} of disk, above the {} free on the output's file system; free some space or lower {lower}",
                    human(e.disk),
                    human(free)
                ),
            });
        }
        Ok(())
    }
}

/// `n` copies of `value`, or a [`SizeError::Alloc`] naming `what` when the memory cannot be had
/// (instead of the abort of `vec![value; n]`).
pub fn try_vec<T: Clone>(n: usize, value: T, what: &str) -> Result<Vec<T>, SizeError> {
    let mut v = Vec::new();
    try_reserve(&mut v, n, what)?;
    v.resize(n, value);
    Ok(v)
}

/// Reserves room for exactly `n` more elements in `v`, or a [`SizeError::Alloc`] naming `what`.
pub fn try_reserve<T>(v: &mut Vec<T>, n: usize, what: &str) -> Result<(), SizeError> {
    v.try_reserve_exact(n).map_err(|_| SizeError::Alloc {
        what: what.to_string(),
        bytes: bytes(&[n as f64], std::mem::size_of::<T>() as u64),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_counts_read_in_binary_units() {
        assert_eq!(human(1536), "1.5 KiB");
        assert_eq!(human(12), "12 bytes");
        assert_eq!(human(2 << 30), "2.0 GiB");
        assert_eq!(human(u64::MAX), "16.0 EiB");
    }

    #[test]
    fn sizes_of_huge_counts_saturate_instead_of_wrapping() {
        assert_eq!(bytes(&[1e9, 1024.0, 1024.0, 3.0], 4), 12_582_912_000_000_000);
        assert_eq!(bytes(&[1e308, 1e308], 8), u64::MAX);
        assert_eq!(bytes(&[f64::NAN], 8), u64::MAX);
        assert_eq!(bytes(&[-1.0, 5.0], 8), u64::MAX);
        assert_eq!(bytes(&[0.0, 5.0], 8), 0);
    }

    fn estimate(memory: u64, disk: u64) -> Estimate {
        Estimate { what: "--frames 1000000 at 1024x1024".into(), memory, disk, lower: "--frames".into() }
    }

    #[test]
    fn requests_above_the_limits_are_refused_naming_size_limit_and_option() {
        let b = Budget { max_memory: Some(1 << 30), available_memory: None, max_disk: Some(50 << 30), free_disk: None };
        assert_eq!(b.check(&estimate(1 << 20, 1 << 20)), Ok(()));
        let m = b.check(&estimate(2 << 30, 0)).unwrap_err().to_string();
        assert!(m.contains("2.0 GiB of memory") && m.contains("--max-memory") && m.contains("--frames"), "{m}");
        let d = b.check(&estimate(0, 8 << 40)).unwrap_err().to_string();
        assert_eq!(
            d,
            "--frames 1000000 at 1024x1024 needs about 8.0 TiB of disk, above --max-disk 50.0 GiB; raise --max-disk or lower --frames"
        );
        let free = Budget { free_disk: Some(1 << 30), ..Budget::default() };
        let f = free.check(&estimate(0, 2 << 30)).unwrap_err().to_string();
        assert!(f.contains("1.0 GiB free"), "{f}");
        // Unknown memory: the 4 GiB default.
        let m = Budget::default().check(&estimate(5 << 30, 0)).unwrap_err().to_string();
        assert!(m.contains("memory available unknown"), "{m}");
    }

    #[test]
    fn an_allocation_that_cannot_be_met_is_an_error_naming_it() {
        let e = try_vec(usize::MAX / 2, 0u64, "the test's table").unwrap_err();
        let m = e.to_string();
        assert!(m.starts_with("cannot allocate the test's table: "), "{m}");
        assert_eq!(try_vec(3, 1u8, "three bytes"), Ok(vec![1, 1, 1]));
    }
}
