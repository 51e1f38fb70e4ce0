//! Requests sized before any work: a few characters of arguments that ask for terabytes, years
//! or an overflow are refused at once, exit 1 (never a signal), with a `--json` error naming the
//! option, the value or the size and the limit, and nothing written: no output, no temporary.
//! Every case here is a refusal before work, so each run takes milliseconds.

use std::path::Path;

use surfcap_testkit::{p, stderr, surfcap};

/// Runs `args` with `--json` in `dir` and checks the refusal: exit code 1 (not a signal), one
/// JSON error on stderr whose text holds every one of `needles`, and `dir` left holding only
/// `keep`. Returns the error's text.
fn refused(dir: &Path, keep: &[&str], args: &[&str], needles: &[&str]) -> String {
    let mut all = vec!["--json"];
    all.extend_from_slice(args);
    let o = surfcap!(&all);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {:?} {}", o.status, stderr(&o));
    let v: serde_json::Value =
        serde_json::from_slice(&o.stderr).unwrap_or_else(|e| panic!("{args:?}: not JSON ({e}): {}", stderr(&o)));
    assert_eq!(v["exit_code"], 1, "{v}");
    let text = format!("{} {}", v["error"].as_str().unwrap_or(""), v["causes"]);
    for n in needles {
        assert!(text.contains(n), "{args:?}: {n:?} not in {text}");
    }
    let mut left: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    left.sort();
    let mut expected: Vec<String> = keep.iter().map(|s| s.to_string()).collect();
    expected.sort();
    assert_eq!(left, expected, "{args:?}: something was left behind");
    text
}

/// A UV-mapped square (two triangles) and an 8 x 8 texture: the smallest input of `appearance`.
fn uv_mesh_and_texture(dir: &Path) {
    std::fs::write(
        dir.join("square.obj"),
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0.1 0.1\nvt 0.9 0.1\nvt 0.9 0.9\nvt 0.1 0.9\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n",
    )
    .unwrap();
    image::RgbImage::from_pixel(8, 8, image::Rgb([200, 120, 40])).save(dir.join("tex.png")).unwrap();
}

#[test]
fn procedural_motion_sizes_are_refused_by_name_before_any_frame_is_made() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("m.subject");
    let o = p(&out);
    // Overflows and nonsense are refused when parsed, naming the option and its range.
    for (args, option, range) in [
        (vec!["--duration", "1e9"], "--duration", "at most 3600"),
        (vec!["--duration", "1e308"], "--duration", "at most 3600"),
        (vec!["--fps", "1e9"], "--fps", "from 0.1 to 10000 fps"),
        (vec!["--bvh-units", "1e308"], "--bvh-units", "from 0.0001 to 100"),
    ] {
        let mut a = vec!["make", "mannequin", "--procedural", "walk", "-o", o];
        a.extend(args);
        refused(d.path(), &[], &a, &[option, range]);
    }
    // Within the ranges, an hour at 1000 fps is about 3.6 million frames:
    // sized before work and refused with the size, the limit and what to lower.
    let t = refused(
        d.path(),
        &[],
        &[
            "make",
            "mannequin",
            "--procedural",
            "walk",
            "--duration",
            "3600",
            "--fps",
            "1000",
            "--max-memory",
            "1G",
            "-o",
            o,
        ],
        &["synthesising 3600001 frames", "of memory", "above the limit of 1.0 GiB", "--max-memory", "--duration"],
    );
    assert!(t.contains("TiB") || t.contains("GiB"), "{t}");
    // And the disk limit, with memory to spare.
    refused(
        d.path(),
        &[],
        &[
            "make",
            "mannequin",
            "--procedural",
            "walk",
            "--duration",
            "600",
            "--max-memory",
            "1T",
            "--max-disk",
            "10M",
            "-o",
            o,
        ],
        &["of disk", "above --max-disk 10.0 MiB", "raise --max-disk or lower --duration"],
    );
}

#[test]
fn a_bvh_resampled_to_a_huge_frame_rate_is_refused_before_retargeting() {
    let d = tempfile::tempdir().unwrap();
    // Two frames five seconds apart: at 10,000 fps, 50,001 frames.
    let bvh = d.path().join("slow.bvh");
    std::fs::write(
        &bvh,
        "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n  End Site\n  {\n    OFFSET 0 10 0\n  }\n}\nMOTION\nFrames: 2\nFrame Time: 5\n0 0 0 0 0 0\n0 0 0 0 0 0\n",
    )
    .unwrap();
    let o = d.path().join("m.subject");
    refused(
        d.path(),
        &["slow.bvh"],
        &["make", "mannequin", "--bvh", p(&bvh), "--fps", "1e7", "-o", p(&o)],
        &["--fps", "10000"],
    );
    refused(
        d.path(),
        &["slow.bvh"],
        &["make", "mannequin", "--bvh", p(&bvh), "--fps", "10000", "--max-memory", "100M", "-o", p(&o)],
        &["synthesising 50001 frames", "above the limit of 100.0 MiB", "--max-memory", "--fps"],
    );
}

#[test]
fn a_head_of_a_billion_frames_per_sequence_is_refused_with_its_size() {
    let d = tempfile::tempdir().unwrap();
    uv_mesh_and_texture(d.path());
    let o = d.path().join("h.subject");
    refused(
        d.path(),
        &["square.obj", "tex.png"],
        &[
            "make",
            "head",
            p(&d.path().join("square.obj")),
            "--frames-per-sequence",
            "1000000000",
            "--max-memory",
            "1G",
            "-o",
            p(&o),
        ],
        &["--frames-per-sequence 1000000000 (3 sequences of 4 vertices)", "of memory", "--max-memory"],
    );
}

#[test]
fn generated_texture_sequences_are_sized_before_the_output_is_started() {
    let d = tempfile::tempdir().unwrap();
    uv_mesh_and_texture(d.path());
    let keep = ["square.obj", "tex.png"];
    let (mesh, tex) = (d.path().join("square.obj"), d.path().join("tex.png"));
    let out = d.path().join("gen");
    let base = ["appearance", "generate", "--mesh", p(&mesh), "--texture", p(&tex), "-o", p(&out)];
    let with = |more: &[&'static str]| -> Vec<&str> { base.iter().copied().chain(more.iter().copied()).collect() };
    // Ranges: a blur of 1e308 once panicked (capacity overflow) inside a started output.
    for (args, option, range) in [
        (["--blur", "1e308"], "--blur", "from 0 to 32"),
        (["--noise", "1e308"], "--noise", "from 0 to 255"),
        (["--max-drift", "1e308"], "--max-drift", "from 0 to 64"),
        (["--noise", "256"], "--noise", "from 0 to 255"),
    ] {
        refused(d.path(), &keep, &with(&args), &[option, range]);
    }
    // A billion frames (the hole masks alone are gigabytes).
    refused(
        d.path(),
        &keep,
        &with(&["--frames", "1000000000", "--max-memory", "1G"]),
        &["--frames 1000000000 at 8x8", "of memory", "above the limit of 1.0 GiB", "--frames or --size"],
    );
    // The largest size, beyond the memory allowed.
    refused(
        d.path(),
        &keep,
        &with(&["--size", "16384", "--frames", "2", "--max-memory", "1G"]),
        &["--frames 2 at 16384x16384", "of memory", "--max-memory"],
    );
    // A million 1024 x 1024 frames with their displacement: terabytes of disk.
    refused(
        d.path(),
        &keep,
        &with(&[
            "--frames",
            "1000000",
            "--size",
            "1024",
            "--displacement-npy",
            "--hole-fraction",
            "0",
            "--max-memory",
            "1T",
            "--max-disk",
            "50G",
        ]),
        &[
            "--frames 1000000 at 1024x1024 with --displacement-npy needs about 13.4 TiB of disk",
            "above --max-disk 50.0 GiB",
            "leave out --displacement-npy",
        ],
    );
}

#[test]
fn a_painted_texture_too_large_for_memory_is_refused() {
    let d = tempfile::tempdir().unwrap();
    uv_mesh_and_texture(d.path());
    let out = d.path().join("paint.png");
    refused(
        d.path(),
        &["square.obj", "tex.png"],
        &[
            "appearance",
            "paint",
            "--mesh",
            p(&d.path().join("square.obj")),
            "--size",
            "16384",
            "--max-memory",
            "1G",
            "-o",
            p(&out),
        ],
        &["--size 16384 (16384x16384 texels) needs about 14.5 GiB of memory", "--max-memory"],
    );
}

#[test]
fn scale_options_that_overflow_name_the_option_and_its_range() {
    let d = tempfile::tempdir().unwrap();
    let m = d.path().join("m");
    refused(
        d.path(),
        &[],
        &["appearance", "build", p(d.path()), "--lambda", "1e308", "-o", p(&m)],
        &["--lambda", "at most 1000"],
    );
}

#[test]
fn iteration_counts_have_documented_bounds() {
    let d = tempfile::tempdir().unwrap();
    let (s, o) = (d.path().join("s.subject"), d.path().join("o"));
    let (s, o) = (p(&s), p(&o));
    refused(
        d.path(),
        &[],
        &["vary", "train", s, "--iterations", "1000000000000", "-o", o],
        &["--iterations", "from 1 to 10000"],
    );
    refused(
        d.path(),
        &[],
        &["remesh-frames", s, "--iterations", "1000000000", "-o", o],
        &["--iterations", "from 1 to 100"],
    );
    refused(d.path(), &[], &["eval", "gpdm", s, "--iterations", "1000000000000"], &["--iterations", "from 1 to 10000"]);
    refused(d.path(), &[], &["eval", "vary", "--iterations", "1000000000000"], &["--iterations", "from 1 to 10000"]);
    // Each HMC option within its range, but together 10^11 leapfrog steps: refused before the
    // model is even opened.
    refused(
        d.path(),
        &[],
        &[
            "vary",
            "sample",
            s,
            "--sequence",
            "walk",
            "--count",
            "1000",
            "--warmup",
            "100000",
            "--thin",
            "10000",
            "--max-leapfrog",
            "10000",
            "-o",
            o,
        ],
        &["--max-leapfrog 10000", "1.010e11 leapfrog steps per body part", "above the 2000000 allowed"],
    );
}

#[test]
fn the_limit_options_are_checked_when_parsed() {
    let d = tempfile::tempdir().unwrap();
    let o = d.path().join("m.subject");
    refused(
        d.path(),
        &[],
        &["make", "mannequin", "--procedural", "walk", "--max-disk", "lots", "-o", p(&o)],
        &["--max-disk"],
    );
    refused(
        d.path(),
        &[],
        &["make", "mannequin", "--procedural", "walk", "--max-memory=-1G", "-o", p(&o)],
        &["--max-memory"],
    );
}
