//! `surfcap-bench`'s plumbing: its options are checked when parsed, its command lines parse
//! (`Cli`), and `distance` reports its memory. Speed is never asserted in tests (the machines
//! are shared).

use clap::Parser;
use surfcap_bench::Cli;
use surfcap_testkit::{stderr, surfcap_bench};

/// `distance` reports the peak memory before and after the matrix, and the matrix's own working
/// memory stays near one slab of triangle data plus the alignment's matrices: 200 frames of
/// 20,000 triangles held whole were 480 MB of triangle frames (the previous computation), held a
/// slab at a time they add well under 250 MB. Memory only: the benchmark's speed is not
/// asserted.
#[test]
fn bench_distance_reports_peak_memory_and_streams_the_triangle_data() {
    let o = surfcap_bench!(&["distance", "--frames", "200", "--triangles", "20000", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!((v["frames"].as_u64(), v["triangles"].as_u64()), (Some(200), Some(20000)), "{v}");
    let (before, peak) = (v["peak_rss_bytes_before_matrix"].as_u64().unwrap(), v["peak_rss_bytes"].as_u64().unwrap());
    assert!(before > 0 && before <= peak, "{v}");
    assert!(peak - before < 250 << 20, "the matrix took {} MB: {v}", (peak - before) >> 20);
}

#[test]
fn numeric_options_are_checked_when_parsed() {
    for (args, option, range) in [
        (vec!["graph", "--frames", "0"], "--frames", ">= 1"),
        (vec!["synth", "--alpha=-0.1"], "--alpha", "> 0"),
        (vec!["distance", "--fps", "0"], "'0' for '--fps <FPS>'", "a finite number > 0"),
    ] {
        let o = surfcap_bench!(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(e.contains(option) && e.contains(range), "{args:?}: {e}");
    }
}

/// Every benchmark of the former `surfcap bench` is a subcommand with the same arguments, and
/// `surfcap bench` is gone from the user's program.
#[test]
fn every_benchmark_parses_with_its_arguments() {
    for args in [
        &["load", "--frames", "2000", "--vertices", "10000"][..],
        &["distance", "--subject", "crane.subject", "--fps", "30"],
        &["interpolate", "crane.subject", "--from", "crane:0", "--to", "crane:90"],
        &["transitions", "--frames", "350", "--slope", "inf"],
        &["graph", "--frames", "2000", "--alpha", "0.1", "--seed", "3"],
        &["synth", "--frames", "400", "--branching", "4"],
        &["smg", "--transitions", "1,3"],
        &["appearance", "--frames", "10", "--flow-scale", "0"],
        &["learn", "--gp-points", "60"],
        &["transfer", "--pairs", "20"],
        &["vary", "--count", "2"],
        &["scale", "--workers", "1,8"],
        &["export", "--format", "abc", "--frames", "1800,3600"],
        &["glb", "--frames", "1800"],
        &["--json", "distance"],
    ] {
        let line = std::iter::once("surfcap-bench").chain(args.iter().copied());
        if let Err(e) = Cli::try_parse_from(line) {
            panic!("{args:?}: {e}");
        }
    }
    let o = surfcap_bench!(&["--help"]);
    let help = String::from_utf8_lossy(&o.stdout);
    assert!(help.contains("synth") && help.contains("distance") && !help.contains("tiles"), "{help}");
}

/// Every benchmark sizes its request from its arguments before any work: huge sizes are
/// refused at once (exit 1, never an abort), with a JSON error naming the arguments, the size
/// and the limit; repetition counts have bounds. `learn --gp-points 1e9` once panicked inside
/// faer's allocation.
#[test]
fn huge_benchmark_requests_are_refused_before_any_work() {
    for (args, needles) in [
        (
            vec!["load", "--frames", "1000000000", "--vertices", "1000000"],
            vec!["--frames 1000000000 --vertices 1000000", "of memory"],
        ),
        (vec!["learn", "--gp-points", "1000000000"], vec!["--gp-points 1000000000", "of memory", "lower --gp-points"]),
        (vec!["distance", "--frames", "100000000"], vec!["--frames 100000000 --triangles 20000", "of memory"]),
        (vec!["transitions", "--frames", "100000000"], vec!["--frames 100000000", "of memory"]),
        (vec!["graph", "--frames", "100000000"], vec!["--frames 100000000", "of memory"]),
        (vec!["synth", "--frames", "100000000"], vec!["--frames 100000000 --vertices 1000", "of memory"]),
        (vec!["smg", "--frames", "100000000"], vec!["--frames 100000000", "of memory"]),
        (vec!["appearance", "--frames", "1000000000"], vec!["--frames 1000000000 --size 1024", "of memory"]),
        (vec!["transfer", "--pairs", "1000000000"], vec!["--pairs 1000000000", "of memory"]),
        (
            vec!["export", "--frames", "1000000000", "--vertices", "1000000"],
            vec!["of memory", "--frames or --vertices"],
        ),
        (vec!["scale", "--frames", "100000000"], vec!["--frames 100000000", "--frames or --triangles"]),
        (vec!["load", "--repeat", "1000000000"], vec!["--repeat", "from 1 to 100"]),
        (vec!["vary", "--iterations", "1000000000000"], vec!["--iterations", "from 1 to 10000"]),
        (vec!["learn", "--gp-restarts", "1000000000"], vec!["--gp-restarts", "from 0 to 100"]),
    ] {
        let mut all = vec!["--json", "--max-memory", "4G"];
        all.extend(&args);
        let o = surfcap_bench!(&all);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {:?} {}", o.status, stderr(&o));
        let v: serde_json::Value =
            serde_json::from_slice(&o.stderr).unwrap_or_else(|e| panic!("{args:?}: not JSON ({e}): {}", stderr(&o)));
        let text = v["error"].as_str().unwrap_or("").to_string();
        for n in needles {
            assert!(text.contains(n), "{args:?}: {n:?} not in {text}");
        }
    }
}
