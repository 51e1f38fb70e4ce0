//! Refusing requests whose output or working memory would exceed what the machine has, before
//! any work. A few characters of arguments (`--steps 100000`, a key at frame 100000, `--time
//! 1e9`, a 2 km curve) ask for hours of search and gigabytes to terabytes of memory; the frame
//! count is estimated from the request, the bytes from frames x vertices (and the timed search's
//! tables), and the request is refused with the size, the limit and the option that raises it.
//!
//! The memory available is the front end's to find out (the command line reads Linux's
//! `/proc/meminfo`); this module only compares ([`SizeLimits::available_memory`]).

use surfcap_formats::export::ExportFormat;
use surfcap_formats::glb::{GLB_MAX_BYTES, estimated_glb_bytes};
use surfcap_mesh::Subject;

use crate::error::{Result, refuse};

/// Frames an animation may have unless raised: 10 minutes at 30 fps.
pub const DEFAULT_MAX_FRAMES: usize = 18_000;

pub use surfcap_mesh::sizing::{UNKNOWN_MEMORY_LIMIT, human};

/// Bounds on what one request may produce.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SizeLimits {
    /// Most frames the animation may have (`--max-frames`).
    pub max_frames: usize,
    /// Most memory the output and the search may need, bytes (`--max-memory`); default half the
    /// memory available.
    pub max_memory: Option<u64>,
    /// The memory available to new allocations when the request starts, bytes, if known.
    pub available_memory: Option<u64>,
    /// Most bytes the output may take on disk (`--max-disk`).
    pub max_disk: Option<u64>,
    /// Free space on the output's file system, bytes, if known.
    pub free_disk: Option<u64>,
}

impl Default for SizeLimits {
    fn default() -> Self {
        SizeLimits {
            max_frames: DEFAULT_MAX_FRAMES,
            max_memory: None,
            available_memory: None,
            max_disk: None,
            free_disk: None,
        }
    }
}

/// What a request will make, estimated before any work.
pub struct Request<'a> {
    /// The arguments responsible, as the user typed them (e.g. `--steps 100000`).
    pub what: String,
    /// Output frames.
    pub frames: f64,
    pub subject: &'a Subject,
    /// Working memory besides the output positions (a search's tables).
    pub search_bytes: u64,
    pub format: ExportFormat,
}

impl SizeLimits {
    /// An error naming the size, the limit and the option that raises it when `r` exceeds
    /// the frame limit, the memory limit, (as glb) the format's 4 GiB, or the disk limit
    /// (`--max-disk`, else the free space of the output's file system).
    pub fn check(&self, r: &Request) -> Result<()> {
        let what = &r.what;
        // NaN frames (never from the callers' finite estimates) are refused too.
        if r.frames.is_nan() || r.frames > self.max_frames as f64 {
            refuse!(
                "{what} asks for about {:.0} frames, above the limit of {} (--max-frames; raise it for longer animations)",
                r.frames,
                self.max_frames
            );
        }
        let frames = r.frames.ceil() as u64;
        let nv = r.subject.topology().n_vertices() as u64;
        let need = frames.saturating_mul(12 * nv).saturating_add(r.search_bytes);
        let (limit, whence) = match (self.max_memory, self.available_memory) {
            (Some(b), _) => (b, "--max-memory".to_string()),
            (None, Some(a)) => (a / 2, format!("half the {} available; raise it with --max-memory", human(a))),
            (None, None) => (UNKNOWN_MEMORY_LIMIT, "memory available unknown; raise it with --max-memory".to_string()),
        };
        if need > limit {
            let search = if r.search_bytes > 0 {
                format!(" and {} of search tables", human(r.search_bytes))
            } else {
                String::new()
            };
            refuse!(
                "{what} needs about {} of memory ({frames} frames x {nv} vertices{search}), above the limit of {} ({whence})",
                human(need),
                human(limit)
            );
        }
        if r.format == ExportFormat::Glb {
            let glb = estimated_glb_bytes(nv as usize, r.subject.topology().n_triangles(), &[frames as usize]);
            if glb > GLB_MAX_BYTES {
                refuse!(
                    "{what} would write a glb of about {} ({frames} frames x {nv} vertices), above the format's limit of {GLB_MAX_BYTES} bytes (4 GiB: its lengths are 32-bit); write --format npy or pc2, or fewer frames",
                    human(glb)
                );
            }
        }
        // The output on disk: binary formats 12 bytes a vertex a frame, text formats about 40
        // and 20 a triangle (OBJ, PLY, USD text), glb as it will be laid out.
        let nt = r.subject.topology().n_triangles() as u64;
        let disk = match r.format {
            ExportFormat::Glb => estimated_glb_bytes(nv as usize, nt as usize, &[frames as usize]),
            ExportFormat::Obj | ExportFormat::Ply | ExportFormat::Usda => {
                frames.saturating_mul((40 * nv).saturating_add(20 * nt))
            }
            // USD crate: points and velocities, 12 bytes each a vertex a frame.
            ExportFormat::Usdc => frames.saturating_mul(24 * nv),
            _ => frames.saturating_mul(12 * nv),
        };
        let budget = surfcap_mesh::sizing::Budget {
            max_memory: Some(u64::MAX),
            available_memory: None,
            max_disk: self.max_disk,
            free_disk: self.free_disk,
        };
        let estimate = surfcap_mesh::sizing::Estimate {
            what: format!("{what} ({frames} frames x {nv} vertices as {:?})", r.format),
            memory: 0,
            disk,
            lower: "the frames asked for".into(),
        };
        budget.check(&estimate).map_err(|e| crate::error::Error::Request(e.to_string()))?;
        Ok(())
    }
}

/// The fastest ground speed (subject units per second) of the subject's sequences: the mean
/// per-frame travel of the vertices' centroid along `axes`. A curve of length L cannot be
/// followed in fewer than L / speed seconds, so frames estimated with it are a lower bound and a
/// refusal is never spurious. `None` when nothing travels.
pub fn fastest_speed(subject: &Subject, axes: &[usize]) -> Option<f64> {
    let speed = |s: &surfcap_mesh::Sequence| {
        let cs: Vec<[f64; 3]> = (0..s.n_frames()).map(|f| surfcap_motion::blend::centre(s.frame(f))).collect();
        let travel: f64 =
            cs.windows(2).map(|w| axes.iter().map(|&k| (w[1][k] - w[0][k]).powi(2)).sum::<f64>().sqrt()).sum();
        travel / (s.n_frames().max(2) - 1) as f64 * subject.fps
    };
    let v = subject.sequences().iter().map(speed).fold(0.0, f64::max);
    (v > 0.0).then_some(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle() -> Subject {
        use surfcap_mesh::{Sequence, Topology, Units, UpAxis};
        let t = Topology::new(3, vec![[0, 1, 2]], None).unwrap();
        let q = Sequence::new("a".to_string(), 3, vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]).unwrap();
        Subject::new("t", t, vec![q], 30.0, UpAxis::PosY, Units::metres()).unwrap()
    }

    #[test]
    fn the_output_on_disk_is_checked_against_the_disk_limit_and_the_free_space() {
        let s = triangle();
        let r = Request {
            what: "--steps 10000".into(),
            frames: 10_000.0,
            subject: &s,
            search_bytes: 0,
            format: ExportFormat::Npy,
        };
        assert!(SizeLimits::default().check(&r).is_ok());
        // 10,000 frames x 3 vertices x 12 bytes = 360,000 bytes.
        let tight = SizeLimits { max_disk: Some(100_000), ..SizeLimits::default() };
        let e = tight.check(&r).unwrap_err().to_string();
        assert!(e.contains("--steps 10000") && e.contains("351.6 KiB of disk") && e.contains("--max-disk"), "{e}");
        let full = SizeLimits { free_disk: Some(1000), ..SizeLimits::default() };
        let e = full.check(&r).unwrap_err().to_string();
        assert!(e.contains("1000 bytes free"), "{e}");
    }

    #[test]
    fn byte_counts_read_in_binary_units() {
        assert_eq!(human(1536), "1.5 KiB");
        assert_eq!(human(12), "12 bytes");
        assert_eq!(human(2 << 30), "2.0 GiB");
    }
}
