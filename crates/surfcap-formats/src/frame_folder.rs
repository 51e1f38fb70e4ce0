//! A folder of per-frame mesh files (`mesh_0000.obj`, `mesh_0001.obj`, ... or `.ply`), read in
//! natural numeric order of file names. The first file is the template: its faces are the
//! topology, and every other frame must have the same vertex count and the same faces
//! (a frame with no faces at all is accepted as positions only). Frames are parsed in parallel;
//! the first error in frame order is reported.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use surfcap_mesh::error::{Error, Location, Result, err};
use surfcap_mesh::natural_order::natural_cmp;
use surfcap_mesh::progress::Progress;
use surfcap_mesh::topology::{Topology, first_triangle_difference};

use crate::obj::read_obj;
use crate::ply::read_ply;

/// Frame file format, chosen by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameFormat {
    Obj,
    Ply,
}

impl FrameFormat {
    pub fn extension(self) -> &'static str {
        match self {
            FrameFormat::Obj => "obj",
            FrameFormat::Ply => "ply",
        }
    }
}

/// Files of the given format in `dir`, in natural order.
pub fn list_frames(dir: &Path, format: FrameFormat) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, "list directory", e))?;
    let mut files: Vec<PathBuf> = Vec::new();
    for e in entries {
        let p = e.map_err(|e| Error::io(dir, "list directory", e))?.path();
        let ext_ok = p.extension().is_some_and(|x| x.eq_ignore_ascii_case(format.extension()));
        // Anything but a folder: a FIFO or socket named like a frame is an error when read, not
        // a frame silently left out.
        if ext_ok && !p.is_dir() {
            files.push(p);
        }
    }
    files.sort_by(|a, b| {
        natural_cmp(&a.file_name().unwrap().to_string_lossy(), &b.file_name().unwrap().to_string_lossy())
    });
    Ok(files)
}

struct Frame {
    positions: Vec<f32>,
    triangles: Vec<[u32; 3]>,
    lines: Vec<usize>,
    topology: Option<Topology>,
}

fn read_frame(path: &Path, format: FrameFormat, want_topology: bool) -> Result<Frame> {
    let (positions, triangles, lines, topology) = match format {
        FrameFormat::Obj => {
            let m = read_obj(path)?;
            let t = if want_topology { Some(m.topology().map_err(|e| e.in_file(path))?) } else { None };
            (m.positions, m.triangles, m.triangle_lines, t)
        }
        FrameFormat::Ply => {
            let m = read_ply(path)?;
            let t = if want_topology { Some(m.topology().map_err(|e| e.in_file(path))?) } else { None };
            (m.positions, m.triangles, Vec::new(), t)
        }
    };
    Ok(Frame { positions, triangles, lines, topology })
}

/// Reads a folder of frames into one topology and contiguous positions.
pub fn read_frame_folder(dir: &Path, format: FrameFormat, progress: &dyn Progress) -> Result<(Topology, Vec<f32>)> {
    let files = list_frames(dir, format)?;
    if files.is_empty() {
        return Err(err!(Empty, "no .{} files: expected one mesh file per frame", format.extension()).in_file(dir));
    }
    progress.start(&format!("reading {} frames", files.len()), files.len() as u64);
    let first = read_frame(&files[0], format, true)?;
    let topology = first.topology.clone().expect("requested");
    let nv = topology.n_vertices();
    let rest: Vec<Result<Vec<f32>>> = files[1..]
        .par_iter()
        .enumerate()
        .map(|(k, path)| {
            let frame_no = k + 1;
            let f = read_frame(path, format, false).map_err(|e| e.at_frame(frame_no))?;
            progress.advance(1);
            if f.positions.len() != 3 * nv {
                return Err(err!(
                    TopologyMismatch,
                    "{} vertices, expected {nv} as in the first frame {}",
                    f.positions.len() / 3,
                    files[0].display()
                )
                .in_file(path)
                .at(Location::Frame(frame_no)));
            }
            if !f.triangles.is_empty()
                && let Some(diff) = first_triangle_difference(topology.triangles(), &f.triangles)
            {
                let i = topology.triangles().iter().zip(&f.triangles).position(|(a, b)| a != b);
                let loc = match i.and_then(|i| f.lines.get(i)) {
                    Some(&line) => Location::FrameLine { frame: frame_no, line },
                    None => Location::Frame(frame_no),
                };
                return Err(err!(TopologyMismatch, "faces differ from the first frame's: {diff}")
                    .in_file(path)
                    .at(loc));
            }
            Ok(f.positions)
        })
        .collect();
    let mut positions = Vec::with_capacity(files.len() * 3 * nv);
    positions.extend_from_slice(&first.positions);
    for r in rest {
        positions.extend_from_slice(&r?);
    }
    progress.finish();
    Ok((topology, positions))
}
