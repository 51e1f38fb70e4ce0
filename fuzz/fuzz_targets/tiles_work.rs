//! A tiny subject's tile work folder, planned and run once, then damaged by the input (files
//! deleted, truncated, overwritten, filled with NaN, copied over each other, replaced by folders
//! or links to other files of the folder, JSON fields of the plan, records and `zarr.json` set
//! to other values) before `status`, `merge`, every job's `run` and `merge` again. Never a
//! panic or an abort; a merge that succeeds gives exactly the products of the clean run (which
//! `crates/surfcap-tiles/tests/tiled_work.rs` proves equal, bit for bit, to the one-machine
//! distance matrix, transition table and sparse essential graph).
//!
//! Input: a sequence of operations of 4 bytes (file, kind, a, b), each kind that writes bytes
//! followed by a length byte and that many bytes.
#![no_main]
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use surfcap_builtin::{WormParams, worm_subject};
use surfcap_mesh::{NoProgress, Sequence, Subject};
use surfcap_tiles::tile_jobs::run_job;
use surfcap_tiles::tile_merge::{merge, status};
use surfcap_tiles::tile_plan::{Stage, WorkParams, create_work, open_work};
use surfcap_tiles::tile_store::Matrix;
use surfcap_tiles::tile_verify::Depth;

struct Clean {
    work: PathBuf,
    /// Every file of the clean work folder after the merge: relative path, bytes.
    files: Vec<(PathBuf, Vec<u8>)>,
    /// The merged products: the six arrays read whole, and `graph_edges.npy`.
    products: Products,
}

#[derive(PartialEq, Debug)]
struct Products {
    f64s: Vec<Vec<u64>>,
    u32s: Vec<Vec<u32>>,
    edges: Vec<u8>,
}

fn products(work: &Path) -> Products {
    let (plan, store, _) = open_work(work).expect("a clean work folder opens");
    let n = plan.frames();
    let f = |m| store.read_f64(m, 0..n, 0..n).expect("merged").iter().map(|x| x.to_bits()).collect();
    let u = |m| store.read_u32(m, 0..n, 0..n).expect("merged");
    Products {
        f64s: vec![f(Matrix::Distances), f(Matrix::TableCost), f(Matrix::PathCosts)],
        u32s: vec![u(Matrix::TableLen), u(Matrix::TableLi), u(Matrix::TableLj)],
        edges: std::fs::read(work.join("graph_edges.npy")).expect("merged"),
    }
}

fn walk(root: &Path, dir: &Path, out: &mut Vec<(PathBuf, Vec<u8>)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            walk(root, &p, out);
        } else {
            out.push((p.strip_prefix(root).unwrap().to_path_buf(), std::fs::read(&p).unwrap()));
        }
    }
}

fn run_all(work: &Path) {
    let Ok((plan, store, frames)) = open_work(work) else { return };
    for stage in Stage::ALL {
        for k in 0..plan.jobs(stage) {
            let _ = run_job(&store, &plan, &frames, stage, k, &NoProgress);
        }
    }
}

fn clean() -> &'static Clean {
    static CLEAN: OnceLock<Clean> = OnceLock::new();
    CLEAN.get_or_init(|| {
        // A folder of this process under the system's temporary folder (the fuzz crate has no
        // tempfile); made afresh at start.
        let dir = std::env::temp_dir().join(format!("surfcap-fuzz-tiles-{}", std::process::id()));
        if dir.exists() {
            std::fs::remove_dir_all(&dir).unwrap();
        }
        std::fs::create_dir_all(&dir).unwrap();
        let a = worm_subject(&WormParams { rings: 4, segments: 4, frames: 6, seed: 1, ..Default::default() }).unwrap();
        let b = worm_subject(&WormParams { rings: 4, segments: 4, frames: 5, seed: 2, ..Default::default() }).unwrap();
        let nv = a.topology().n_vertices();
        let seqs = vec![
            Sequence::new("wave", nv, a.sequences()[0].positions().to_vec()).unwrap(),
            Sequence::new("coil", nv, b.sequences()[0].positions().to_vec()).unwrap(),
        ];
        let subject = Subject::new("tube", a.topology().clone(), seqs, 30.0, a.up_axis, a.units.clone()).unwrap();
        let cache = dir.join("tube.subject");
        surfcap_mesh::cache::write_cache(&cache, &subject, false, &NoProgress).unwrap();
        let clean = dir.join("clean");
        let params = WorkParams {
            metric: "deformation".into(),
            w: 0.01,
            l_min: 2,
            l_max: 3,
            slope: Some(3),
            alpha: surfcap_motion_alpha(),
            k: 3,
        };
        create_work(&cache, &clean, 4, params).unwrap();
        run_all(&clean);
        let (plan, store, _) = open_work(&clean).unwrap();
        merge(&store, &plan).expect("the clean run merges");
        let mut files = Vec::new();
        walk(&clean, &clean, &mut files);
        let products = products(&clean);
        Clean { work: dir.join("work"), files, products }
    })
}

fn surfcap_motion_alpha() -> surfcap_tiles::tile_plan::Alpha {
    surfcap_tiles::tile_plan::Alpha::new(0.05).unwrap()
}

/// A JSON value's text picked by `b` (numbers at the edges, wrong types, the payload).
fn value(b: u8, payload: &[u8]) -> Vec<u8> {
    let text: &str = match b % 12 {
        0 => "0",
        1 => "1",
        2 => "1000000000000",
        3 => "18446744073709551615",
        4 => "-1",
        5 => "1e12",
        6 => "\"nope\"",
        7 => "null",
        8 => "[]",
        9 => "{}",
        10 => "1e308",
        _ => return payload.to_vec(),
    };
    text.as_bytes().to_vec()
}

/// Replaces the value after the a-th `": ` of a JSON text (up to the next `,`, newline or `}`)
/// with `v`: a field of the plan, a record or a `zarr.json` set to another value.
fn set_field(doc: &[u8], a: usize, v: &[u8]) -> Vec<u8> {
    let starts: Vec<usize> = doc.windows(3).enumerate().filter(|(_, w)| w == b"\": ").map(|(i, _)| i + 3).collect();
    let Some(&s) = starts.get(a % starts.len().max(1)) else { return doc.to_vec() };
    let e = doc[s..].iter().position(|c| matches!(c, b',' | b'\n' | b'}')).map_or(doc.len(), |k| s + k);
    [&doc[..s], v, &doc[e..]].concat()
}

fn mutate(work: &Path, files: &[PathBuf], data: &[u8]) {
    let mut at = 0;
    while at + 4 <= data.len() {
        let (f, kind, a, b) = (data[at] as usize, data[at + 1], data[at + 2] as usize, data[at + 3]);
        at += 4;
        let mut payload: &[u8] = &[];
        if matches!(kind % 10, 2 | 4 | 7) && at < data.len() {
            let len = (data[at] as usize).min(data.len() - at - 1);
            payload = &data[at + 1..at + 1 + len];
            at += 1 + len;
        }
        let rel = &files[f % files.len()];
        let path = work.join(rel);
        let bytes = std::fs::read(&path).unwrap_or_default();
        let _ = match kind % 10 {
            0 => std::fs::remove_file(&path),
            1 => std::fs::write(&path, &bytes[..(a * 256 + b as usize) % (bytes.len() + 1)]),
            2 => {
                let mut x = bytes;
                for (i, p) in payload.iter().enumerate() {
                    if !x.is_empty() {
                        let k = (a * 256 + b as usize + i) % x.len();
                        x[k] ^= p;
                    }
                }
                std::fs::write(&path, x)
            }
            3 => std::fs::remove_file(&path).and_then(|_| std::fs::create_dir(&path)),
            4 => std::fs::write(&path, payload),
            5 => {
                let nan = f64::NAN.to_le_bytes();
                std::fs::write(&path, (0..bytes.len()).map(|i| nan[i % 8]).collect::<Vec<u8>>())
            }
            6 => std::fs::write(&path, std::fs::read(work.join(&files[a % files.len()])).unwrap_or_default()),
            7 => std::fs::write(&path, set_field(&bytes, a, &value(b, payload))),
            8 => std::fs::remove_file(&path)
                .and_then(|_| std::os::unix::fs::symlink(work.join(&files[a % files.len()]), &path)),
            _ => std::fs::write(&path, [bytes.as_slice(), bytes.as_slice()].concat()),
        };
    }
}

fuzz_target!(|data: &[u8]| {
    let clean = clean();
    let work = &clean.work;
    if work.symlink_metadata().is_ok() {
        std::fs::remove_dir_all(work).unwrap();
    }
    for (rel, bytes) in &clean.files {
        let p = work.join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, bytes).unwrap();
    }
    let names: Vec<PathBuf> = clean.files.iter().map(|(r, _)| r.clone()).collect();
    mutate(work, &names, data);

    let Ok((plan, store, _)) = open_work(work) else { return };
    let quick = status(&store, &plan, Depth::Sizes);
    let full = status(&store, &plan, Depth::Contents);
    assert!(full.problems.len() >= quick.problems.len(), "a full check finds at least what sizes find");
    if merge(&store, &plan).is_ok() {
        assert!(full.problems.is_empty(), "merged over problems: {:?}", full.problems);
        assert_eq!(products(work), clean.products, "a merge over a damaged folder");
    }
    drop(store);
    run_all(work);
    let Ok((plan, store, _)) = open_work(work) else { return };
    if merge(&store, &plan).is_ok() {
        assert_eq!(products(work), clean.products, "a merge after running the damaged jobs again");
    }
});
