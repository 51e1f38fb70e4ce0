//! Frame sets (every frame its own vertices and triangles, as the per-frame
//! reconstructions of Huang et al. 2009): a folder of frames with different connectivity imports
//! as a `.frames` folder with a note, `info` summarises it, commands that need one topology say
//! what it is; and `remesh-frames` makes frame sets with known answers from the Vlasic crane and
//! the CMU-driven mannequin: different vertex counts and connectivity per frame, every new
//! vertex on the source surface where its correspondence says, the source close to the new
//! surface, closed 2-manifolds, the same result on 1 and 2 threads.

use std::path::Path;
use std::time::Instant;

use surfcap_builtin::frame_remeshing::{
    RemeshFramesOptions, distances_to_surface, mean_edge_length, remesh_subject_frames, vertex_neighbours,
};
use surfcap_formats::import::{ImportOptions, ImportedData, open_any};
use surfcap_mesh::{FrameSet, NoProgress, Subject};
use surfcap_testkit::{p, stderr, surfcap};

const TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
/// The tetrahedron with its bottom face split at (0.5, 0.5, 0): five vertices.
const SPLIT: &str =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0.5 0.5 0\nf 1 3 5\nf 1 5 2\nf 1 2 4\nf 2 5 4\nf 5 3 4\nf 1 4 3\n";

fn json(o: &std::process::Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stdout)))
}

#[test]
fn a_folder_of_frames_with_their_own_topologies_imports_as_a_frame_set_and_subject_commands_say_so() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("capture");
    std::fs::create_dir(&dir).unwrap();
    for (k, text) in [TETRA, SPLIT, TETRA].iter().enumerate() {
        std::fs::write(dir.join(format!("frame_{k}.obj")), text).unwrap();
    }
    // Refused as a subject cache, with the way out.
    let subject = tmp.path().join("x.subject");
    let o = surfcap!(&["import", p(&dir), "--fps", "25", "-o", p(&subject)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains(&format!("e.g. -o {}", tmp.path().join("x.frames").display())), "{}", stderr(&o));
    assert!(!subject.exists());
    let frames = tmp.path().join("x.frames");
    let o = surfcap!(&["import", p(&dir), "--fps", "25", "-o", p(&frames)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let note = format!(
        "frames of {} have different vertices/triangles (frame 1: 5 vertices, frame 0: 4): imported as a frame set; \
         commands that need one topology cannot use it",
        dir.display()
    );
    assert!(stderr(&o).contains(&note), "{}", stderr(&o));
    assert!(frames.join("frameset.json").is_file() && frames.join("faces_0.npy").is_file());

    let o = surfcap!(&["info", p(&frames), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let d = json(&o);
    assert_eq!((d["frames"].as_u64(), d["shared_topology"].as_bool()), (Some(3), Some(false)));
    assert_eq!((d["vertices"]["min"].as_u64(), d["vertices"]["max"].as_u64()), (Some(4), Some(5)));
    assert_eq!((d["triangles"]["min"].as_u64(), d["triangles"]["max"].as_u64()), (Some(4), Some(6)));
    assert_eq!(d["sequences"][0]["name"], "capture");
    let o = surfcap!(&["info", p(&frames)]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("vertices    4 to 5 per frame"));

    // Commands that need one topology: the .frames folder and the source folder alike.
    let refusal = "is a frame set (every frame has its own vertices and triangles; 3 frames): this command needs one \
                   shared topology";
    for args in [
        vec!["distance", p(&frames), "-o", "d.npy"],
        vec!["export", p(&dir), "--fps", "25", "--format", "glb", "-o", "x.glb"],
        vec!["interpolate", p(&frames), "--from", "capture:0", "--to", "capture:2", "-o", "i.glb"],
        vec!["distance", p(&dir), "--fps", "25", "-o", "d.npy"],
    ] {
        let mut args = args;
        let out = tmp.path().join(args[args.len() - 1]);
        let n = args.len();
        args[n - 1] = p(&out);
        let o = surfcap!(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(e.contains(refusal) && e.contains("Huang et al.'s surface motion graph"), "{args:?}: {e}");
        assert!(!out.exists());
    }
    // A .frames folder exports to the formats that hold per-frame topology, and only to them.
    let out = tmp.path().join("x.ply");
    let o = surfcap!(&["export", p(&frames), "--format", "ply", "-o", p(&out)]);
    assert!(
        stderr(&o).contains("cannot be written as Ply, which holds one topology: expected glb, abc or obj"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    // As glb: a mesh per frame, valid glTF, played frame by frame by three.js, read back exactly.
    let glb = tmp.path().join("x.glb");
    let o = surfcap!(&["export", p(&frames), "--format", "glb", "-o", p(&glb), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    surfcap_testkit::validate_glb(std::slice::from_ref(&glb));
    let played = &surfcap_testkit::three_load_glb(std::slice::from_ref(&glb))[0];
    assert_eq!((played["kind"].as_str(), played["frames"][0].as_u64()), (Some("frame-set"), Some(3)), "{played}");
    assert!(played["distinct_vertex_counts"][0].as_u64().unwrap() >= 2, "{played}");
    let back = tmp.path().join("back.frames");
    let o = surfcap!(&["import", p(&glb), "-o", p(&back), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (a, b) = (
        surfcap_mesh::frame_set_cache::read_frame_set(&frames, &surfcap_mesh::NoProgress).unwrap(),
        surfcap_mesh::frame_set_cache::read_frame_set(&back, &surfcap_mesh::NoProgress).unwrap(),
    );
    assert!(a.sequences()[0].frames() == b.sequences()[0].frames(), "the glb reads back as the same frames");
    // A command that needs one topology refuses the glb, saying what it holds.
    let o = surfcap!(&["distance", p(&glb), "-o", p(&tmp.path().join("d.npy"))]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains(refusal), "{}", stderr(&o));

    // A subject written as a frame set keeps its one topology, and reads back as that subject.
    let same = tmp.path().join("same");
    std::fs::create_dir(&same).unwrap();
    for k in 0..2 {
        std::fs::write(same.join(format!("f_{k}.obj")), TETRA).unwrap();
    }
    let as_set = tmp.path().join("same.frames");
    let o = surfcap!(&["import", p(&same), "--fps", "25", "--as-frame-set", "-o", p(&as_set), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let d = json(&surfcap!(&["info", p(&as_set), "--json"]));
    assert_eq!(d["shared_topology"].as_bool(), Some(true));
    let o = surfcap!(&["distance", p(&as_set), "-o", p(&tmp.path().join("d.npy")), "--cache-dir", p(tmp.path())]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("frames all share one topology: used as a subject"), "{}", stderr(&o));
}

/// What the tests check of a frame set re-meshed from `source`, and measure.
struct Measured {
    vertex_counts: Vec<usize>,
    /// Largest distance of a new vertex to the source frame's surface, over the bounding box's diagonal.
    on_surface: f64,
    /// Largest and mean distance of a source vertex to the new surface, over the new mean edge length.
    back_max: f64,
    back_mean: f64,
}

fn check_against_source(set: &FrameSet, source: &Subject) -> Measured {
    let tris = source.topology().triangles();
    let (mut on_surface, mut back_max, mut back_sum, mut back_n) = (0f64, 0f64, 0f64, 0usize);
    let mut vertex_counts = Vec::new();
    for (q, seq) in set.sequences().iter().enumerate() {
        let (k, src) = source.sequence(&seq.name).unwrap();
        let rows = &seq.correspondence().expect("remesh-frames writes the correspondence").rows;
        let mut row = 0;
        for (f, frame) in seq.frames().iter().enumerate() {
            let label = set.frame_index().label(set.frame_index().global(q, f).unwrap());
            let sp = src.frame(f);
            let (lo, hi) = surfcap_mesh::bounding_box(sp);
            let diag = (0..3).map(|c| ((hi[c] - lo[c]) as f64).powi(2)).sum::<f64>().sqrt();
            let t = frame.topology();
            assert!(t.is_closed_manifold(), "{label}: not a closed 2-manifold (in {}, source sequence {k})", seq.name);
            assert_eq!(t.count_degenerate_triangles(frame.positions(), 1e-12), 0, "{label}");
            vertex_counts.push(t.n_vertices());
            // On the source surface, where the correspondence says.
            let d = distances_to_surface(frame.positions(), sp, tris);
            on_surface = on_surface.max(d.iter().copied().fold(0.0, f64::max) / diag);
            for v in 0..t.n_vertices() {
                let c = &rows[4 * row..4 * row + 4];
                let tri = tris[c[0] as usize];
                for x in 0..3 {
                    let want: f64 = (0..3).map(|j| c[1 + j] * sp[3 * tri[j] as usize + x] as f64).sum();
                    assert!((want - frame.positions()[3 * v + x] as f64).abs() < 1e-5 * diag, "{label}: vertex {v}");
                }
                row += 1;
            }
            let mean_edge = mean_edge_length(frame.positions(), &vertex_neighbours(t.n_vertices(), t.triangles()));
            let back = distances_to_surface(sp, frame.positions(), t.triangles());
            back_max = back_max.max(back.iter().copied().fold(0.0, f64::max) / mean_edge);
            back_sum += back.iter().sum::<f64>() / mean_edge;
            back_n += back.len();
        }
        assert_eq!(row * 4, rows.len());
    }
    // Connectivity differs: no two consecutive frames share a topology.
    for g in 1..set.frame_count() {
        let (a, b) = (set.frame(g - 1).unwrap(), set.frame(g).unwrap());
        assert_ne!(a.topology(), b.topology(), "{} and the frame before share a topology", set.frame_index().label(g));
    }
    Measured { vertex_counts, on_surface, back_max, back_mean: back_sum / back_n as f64 }
}

fn read_frames(path: &Path) -> FrameSet {
    match open_any(path, &ImportOptions::default(), &NoProgress).unwrap() {
        ImportedData::FrameSet(f) => f.frame_set,
        ImportedData::Subject(_) => panic!("{} is not a frame set", path.display()),
    }
}

#[test]
fn vlasic_crane_frames_remeshed_on_their_own_stay_on_the_capture() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let crane = data.join("vlasic2008/crane");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("crane.frames");
    let o = surfcap!(&["remesh-frames", p(&crane), "-o", p(&out), "--seed", "5", "--frames", "6", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r = json(&o);
    eprintln!(
        "crane: {} s per frame of {} vertices",
        r["seconds_per_frame"].as_f64().unwrap(),
        r["source_vertices"].as_u64().unwrap()
    );
    let set = read_frames(&out);
    let source = surfcap_formats::import::open_subject(&crane, &ImportOptions::default(), &NoProgress).unwrap().subject;
    assert_eq!(set.frame_count(), 6);
    assert_eq!(set.frame_index().label(5), "crane:5");
    let m = check_against_source(&set, &source);
    eprintln!(
        "crane: vertices {:?}; new -> source {:.1e} of the diagonal; source -> new max {:.3} mean {:.4} mean edges",
        m.vertex_counts, m.on_surface, m.back_max, m.back_mean
    );
    let mut distinct = m.vertex_counts.clone();
    distinct.sort_unstable();
    distinct.dedup();
    assert!(distinct.len() >= 5, "vertex counts {:?}", m.vertex_counts);
    // Around the source's 10,002 vertices, each frame within the +-10% edge length's reach.
    assert!(m.vertex_counts.iter().all(|&n| (7000..=13000).contains(&n)), "{:?}", m.vertex_counts);
    assert!(m.on_surface < 1e-6, "{}", m.on_surface);
    assert!(m.back_max < 1.5 && m.back_mean < 0.1, "max {} mean {}", m.back_max, m.back_mean);

    // The same frames on 1 and 2 threads, in the library, are those the program wrote.
    let opts = RemeshFramesOptions { seed: 5, frames: Some(2), ..Default::default() };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| remesh_subject_frames(&source, &opts, &NoProgress).unwrap())
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one, two);
    for g in 0..2 {
        assert_eq!(one.frame(g), set.frame(g));
    }
    // A full Vlasic frame, timed alone.
    let t0 = Instant::now();
    let single = RemeshFramesOptions { seed: 9, frames: Some(1), ..Default::default() };
    let f = remesh_subject_frames(&source, &single, &NoProgress).unwrap();
    eprintln!(
        "crane:0 re-meshed in {:.2} s ({} -> {} vertices)",
        t0.elapsed().as_secs_f64(),
        source.topology().n_vertices(),
        f.frame(0).unwrap().n_vertices()
    );
}

#[test]
fn the_cmu_driven_mannequin_remeshed_per_frame_is_a_frame_set_with_known_answers() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let subject = tmp.path().join("cmu.subject");
    let bvh = data.join("cmu_bvh/16_15.bvh");
    let o = surfcap!(&["make", "mannequin", "--bvh", p(&bvh), "--vertices", "4000", "-o", p(&subject), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = tmp.path().join("cmu.frames");
    let o = surfcap!(&[
        "remesh-frames",
        p(&subject),
        "-o",
        p(&out),
        "--seed",
        "2",
        "--frames",
        "10",
        "--vertices",
        "3000",
        "--sequences",
        "16_15"
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let set = read_frames(&out);
    let source = surfcap_mesh::cache::read_cache(&subject, &NoProgress).unwrap();
    assert!(source.topology().is_closed_manifold());
    assert_eq!(set.frame_count(), 10);
    let m = check_against_source(&set, &source);
    eprintln!(
        "mannequin: vertices {:?}; new -> source {:.1e} of the diagonal; source -> new max {:.3} mean {:.4} mean edges",
        m.vertex_counts, m.on_surface, m.back_max, m.back_mean
    );
    let mut distinct = m.vertex_counts.clone();
    distinct.sort_unstable();
    distinct.dedup();
    assert!(distinct.len() >= 8, "vertex counts {:?}", m.vertex_counts);
    assert!(m.vertex_counts.iter().all(|&n| (2100..=3900).contains(&n)), "{:?}", m.vertex_counts);
    assert!(m.on_surface < 1e-6, "{}", m.on_surface);
    assert!(m.back_max < 1.0 && m.back_mean < 0.1, "max {} mean {}", m.back_max, m.back_mean);
    // The frame set keeps the subject's labels and tags; it is refused where one topology is needed.
    assert_eq!(set.sequences()[0].tags, source.sequences()[0].tags);
    let o = surfcap!(&["distance", p(&out), "-o", p(&tmp.path().join("d.npy"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("is a frame set (every frame has its own vertices and triangles; 10 frames)"));
}
