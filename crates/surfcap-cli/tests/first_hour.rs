//! What a new user meets in the first hour, end to end: data options that resolve the same
//! from any working folder, a subject named after what its sources share, wrong sequence names
//! answered with the ones that exist, frames written `sequence:frame`, one spelling per unit,
//! `surfcap synth` alone listing what it does (built-in subjects made by `surfcap make`), global flags after each command's own options,
//! BVH clips resampled aloud, and `report --include` that never drops a file silently.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use surfcap_testkit::{p, stderr, surfcap};

const EXE: &str = env!("CARGO_BIN_EXE_surfcap");

/// A tetrahedron frame, `k` shifting its apex so frames differ.
fn tetra(k: usize) -> String {
    let z = 1.0 + 0.1 * k as f64;
    format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 {z}\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n")
}

/// Two folders of three OBJ frames each, `knight_Walk` and `knight_Run`, under `dir/clips`.
fn two_clips(dir: &Path) -> Vec<PathBuf> {
    ["knight_Walk", "knight_Run"]
        .iter()
        .map(|name| {
            let d = dir.join("clips").join(name);
            std::fs::create_dir_all(&d).unwrap();
            for k in 0..3 {
                std::fs::write(d.join(format!("frame_{k:03}.obj")), tetra(k)).unwrap();
            }
            d
        })
        .collect()
}

/// `surfcap` run in `cwd` with `SURFCAP_DATA` set to `data` (or removed).
fn run_in(cwd: &Path, data: Option<&Path>, args: &[&str]) -> Output {
    let mut c = Command::new(EXE);
    c.current_dir(cwd).args(args);
    match data {
        Some(d) => c.env("SURFCAP_DATA", d),
        None => c.env_remove("SURFCAP_DATA"),
    };
    c.output().unwrap()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn data_options_resolve_surfcap_data_then_the_checkout_from_any_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("my-data");
    std::fs::create_dir(&data).unwrap();
    let out = tmp.path().join("frames");
    // With SURFCAP_DATA set, `appearance generate` looks for the head scan there (it is
    // missing: the error names the folder), not in ../shared/data of the working folder.
    let o =
        run_in(tmp.path(), Some(&data), &["appearance", "generate", "--frames", "2", "--size", "64", "-o", p(&out)]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains(&data.join("leeperrysmith_head").display().to_string()), "{}", stderr(&o));
    // Without it, the default is the shared/data folder beside the checkout, whatever the
    // working folder, and every data option's help says so.
    let checkout = surfcap_testkit::workspace_root().parent().unwrap().join("shared").join("data");
    for args in [
        &["appearance", "generate", "--help"][..],
        &["eval", "appearance", "--help"],
        &["eval", "interchange", "--help"],
        &["eval", "transfer", "--help"],
        &["reproduce", "--help"],
    ] {
        let o = run_in(tmp.path(), None, args);
        let help = stdout(&o);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        assert!(help.contains("$SURFCAP_DATA"), "{args:?}: {help}");
        assert!(help.contains(&format!("[default: {}]", checkout.display())), "{args:?}: {help}");
    }
    let o = run_in(tmp.path(), Some(&data), &["eval", "interchange", "--help"]);
    assert!(stdout(&o).contains(&format!("[default: {}]", data.display())), "{}", stdout(&o));
}

#[test]
fn a_subject_of_several_sources_is_named_after_what_they_share() {
    let tmp = tempfile::tempdir().unwrap();
    let clips = two_clips(tmp.path());
    let subject = tmp.path().join("k.subject");
    let o = surfcap!(&["import", p(&clips[0]), p(&clips[1]), "--fps", "30", "-o", p(&subject)]);
    assert!(o.status.success(), "{}", stderr(&o));
    // import says which name it chose and why.
    assert!(
        stderr(&o).contains(r#"subject named "knight" after the prefix the sources' names share"#),
        "{}",
        stderr(&o)
    );
    let o = surfcap!(&["info", p(&subject), "--json"]);
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(info["subject"], "knight", "{info}");

    // A wrong --sequences name in `view` is answered with the sequences there are (before
    // the server starts).
    let o = surfcap!(&["view", p(&subject), "--sequences", "knight_Walk,knight_Jog"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains(r#"no sequence named "knight_Jog" in what was given; it has knight_Walk, knight_Run"#),
        "{}",
        stderr(&o)
    );

    // interpolate names its frames `sequence:frame`.
    let blend = tmp.path().join("blend.glb");
    let o = surfcap!(&[
        "interpolate",
        p(&subject),
        "--from",
        "knight_Walk:1",
        "--to",
        "4",
        "--steps",
        "3",
        "--method",
        "linear",
        "-o",
        p(&blend)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("interpolation of knight_Walk:1 -> knight_Run:1 in 3 poses"), "{}", stdout(&o));
}

#[test]
fn units_are_written_with_their_symbol() {
    let tmp = tempfile::tempdir().unwrap();
    let clips = two_clips(tmp.path());
    let subject = tmp.path().join("k.subject");
    let o =
        surfcap!(&["import", p(&clips[0]), "--fps", "30", "--units", "metres (approx.)", "-o", p(&subject), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = surfcap!(&["info", p(&subject)]);
    let text = stdout(&o);
    assert!(text.lines().any(|l| l.starts_with("bounds") && l.ends_with(") m")), "{text}");
    assert!(text.lines().any(|l| l.split_whitespace().collect::<Vec<_>>() == ["units", "m"]), "{text}");
    assert!(!text.contains("metres"), "{text}");
    let o = surfcap!(&[
        "import",
        p(&clips[0]),
        "--fps",
        "30",
        "--units",
        "model units",
        "-o",
        p(&subject),
        "--quiet",
        "--force"
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&surfcap!(&["info", p(&subject)]));
    assert!(text.contains(r#"units       units (not metric: "model units")"#), "{text}");
}

#[test]
fn synth_alone_lists_its_subcommands_and_global_flags_come_last_in_help() {
    let o = surfcap!(&["synth"]);
    assert!(!o.status.success());
    let text = format!("{}{}", stdout(&o), stderr(&o));
    for word in ["path", "keyposes", "reach", "surfcap make mannequin | head"] {
        assert!(text.contains(word), "{word}: {text}");
    }
    assert!(!text.contains("is required") && !text.contains("--procedural"), "{text}");
    // Built-in subjects have their own command.
    let help = stdout(&surfcap!(&["make", "mannequin", "--help"]));
    for word in ["--procedural", "--bvh", "--uv-atlas", "--output <OUTPUT>"] {
        assert!(help.contains(word), "{word}: {help}");
    }
    let o = surfcap!(&["make", "mannequin", "--procedural", "walk"]);
    assert!(!o.status.success() && stderr(&o).contains("--output"), "{}", stderr(&o));
    // The older flat form still builds, with a note naming the new command.
    let tmp = tempfile::tempdir().unwrap();
    let old = tmp.path().join("old.subject");
    let o = surfcap!(&["synth", "--procedural", "walk", "--duration", "0.5", "--vertices", "1000", "-o", p(&old)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("is now `surfcap make mannequin --bvh | --procedural ...`"), "{}", stderr(&o));
    let new = tmp.path().join("new.subject");
    let o = surfcap!(&[
        "make",
        "mannequin",
        "--procedural",
        "walk",
        "--duration",
        "0.5",
        "--vertices",
        "1000",
        "-o",
        p(&new)
    ]);
    assert!(o.status.success() && !stderr(&o).contains("is now"), "{}", stderr(&o));
    let info = |s: &Path| stdout(&surfcap!(&["info", p(s), "--json"]));
    assert_eq!(info(&old).replace("old.subject", "x"), info(&new).replace("new.subject", "x"));

    let global = ["--quiet", "--json", "--force", "--max-memory", "--max-disk", "--help"];
    for args in [
        &["synth", "path", "--help"][..],
        &["import", "--help"],
        &["distance", "--help"],
        &["make", "mannequin", "--help"],
    ] {
        let o = surfcap!(args);
        let help = stdout(&o);
        // The options' lines, in order: the flag each starts with.
        let flags: Vec<&str> = help
            .lines()
            .map(str::trim_start)
            .filter(|l| l.starts_with('-'))
            .map(|l| l.split([' ', ',', '=']).find(|w| w.starts_with("--")).unwrap_or(l))
            .collect();
        let first_global = flags.iter().position(|f| global.contains(f)).unwrap();
        assert!(first_global > 0, "{args:?}: {flags:?}");
        assert!(
            flags[first_global..].iter().all(|f| global.contains(f)),
            "{args:?}: own options after the global ones: {flags:?}"
        );
    }
    // The top-level summary of `appearance` covers its subcommands, not only `generate`.
    let help = stdout(&surfcap!(&["--help"]));
    let line = help.lines().find(|l| l.trim_start().starts_with("appearance")).unwrap();
    assert!(line.contains("build") && line.contains("complete"), "{line}");
}

#[test]
fn transition_and_key_pose_table_name_frames_as_sequence_frame() {
    let tmp = tempfile::tempdir().unwrap();
    let walker = surfcap_testkit::procedural_walker!(tmp.path());
    let cache = tmp.path().join("cache");
    let t = tmp.path().join("t.glb");
    let o =
        surfcap!(&["transition", p(&walker), "--from", "walk:20", "--to", "91", "-o", p(&t), "--cache-dir", p(&cache)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("transition walk:20 -> jog:30:"), "{}", stdout(&o));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(tmp.path().join("t.transition.json")).unwrap()).unwrap();
    assert_eq!((report["from_frame"].as_str(), report["to_frame"].as_str()), (Some("walk:20"), Some("jog:30")));

    let keys = tmp.path().join("keys.csv");
    std::fs::write(&keys, "frame,time\nwalk:10,0.5s\n81,2s\n").unwrap();
    let k = tmp.path().join("k.glb");
    let o = surfcap!(&["synth", "keyposes", p(&walker), "--keys", p(&keys), "-o", p(&k), "--cache-dir", p(&cache)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    let row = |label: &str| text.lines().find(|l| l.starts_with(label)).unwrap_or_else(|| panic!("{label}: {text}"));
    assert_eq!(row("key pose").split_whitespace().skip(2).collect::<Vec<_>>(), ["walk:10", "jog:20"], "{text}");
    assert_eq!(row("asked at frame").split_whitespace().skip(3).collect::<Vec<_>>(), ["15", "60"], "{text}");
    assert!(row("obtained at frame").split_whitespace().count() == 5, "{text}");

    // --help says a larger alpha gives a denser graph: so it does.
    let density = |alpha: &str| {
        let g = tmp.path().join(format!("graph-{alpha}"));
        let o = surfcap!(&[
            "--json",
            "graph",
            "build",
            p(&walker),
            "--alpha",
            alpha,
            "-o",
            p(&g),
            "--cache-dir",
            p(&cache)
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        v["density"].as_f64().unwrap()
    };
    let help = stdout(&surfcap!(&["graph", "build", "--help"]));
    assert!(help.contains("larger gives a denser graph"), "{help}");
    let (low, high) = (density("0.01"), density("0.5"));
    assert!(high > low, "density {low} at alpha 0.01, {high} at 0.5");

    // A missing parts file is named as a parts file.
    let o = surfcap!(&[
        "vary",
        "train",
        p(&walker),
        "--sequences",
        "walk,jog",
        "--parts",
        "missing.json",
        "-o",
        p(&tmp.path().join("vm"))
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("body parts: missing.json: cannot read"), "{}", stderr(&o));
}

#[test]
fn clips_at_other_rates_are_resampled_with_a_note() {
    let Some(data) = surfcap_testkit::shared_data() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    // The 120 fps dance cut to its first 12 frames, then a 30 fps walk.
    let dance = std::fs::read_to_string(data.join("cmu_bvh/05_18.bvh")).unwrap();
    let (head, motion) = dance.split_once("Frame Time:").unwrap();
    let mut lines = motion.lines();
    let frame_time = lines.next().unwrap();
    let short_head = head.replace("Frames: 1830", "Frames: 12");
    assert_ne!(short_head, head, "the dance's frame count line");
    let cut = format!("{short_head}Frame Time:{frame_time}\n{}\n", lines.take(12).collect::<Vec<_>>().join("\n"));
    let first = tmp.path().join("dance.bvh");
    std::fs::write(&first, cut).unwrap();
    let walk = data.join("cmu_bvh/16_36.bvh");
    let s = tmp.path().join("m.subject");
    let o = surfcap!(&["make", "mannequin", "--bvh", p(&first), p(&walk), "--vertices", "1000", "-o", p(&s)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let note = format!("{} (30 fps) resampled to 120 fps (the first file's, {})", walk.display(), first.display());
    assert!(stderr(&o).contains(&note), "{}", stderr(&o));
}

#[test]
fn report_include_shows_a_png_named_alone_and_refuses_what_it_cannot_show() {
    let tmp = tempfile::tempdir().unwrap();
    let clips = two_clips(tmp.path());
    let plots = tmp.path().join("plots");
    std::fs::create_dir(&plots).unwrap();
    std::fs::write(plots.join("t-dtw.png"), surfcap_testkit::png_1x1([200, 30, 30])).unwrap();
    std::fs::write(plots.join("t-dtw.svg"), "<svg xmlns=\"http://www.w3.org/2000/svg\"/>").unwrap();
    let cache = tmp.path().join("cache");
    let out = tmp.path().join("report");
    let png = plots.join("t-dtw.png");
    let o = surfcap!(&[
        "report",
        p(&clips[0]),
        "--fps",
        "30",
        "-o",
        p(&out),
        "--include",
        p(&png),
        "--cache-dir",
        p(&cache)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("t-dtw.png\""), "{html}");
    assert!(out.join("plots/t-dtw.png").is_file());
    // Both in a folder: the SVG stands for the pair.
    let o = surfcap!(&[
        "report",
        p(&clips[0]),
        "--fps",
        "30",
        "-o",
        p(&out),
        "--include",
        p(&plots),
        "--cache-dir",
        p(&cache)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("t-dtw.svg\"") && !html.contains("t-dtw.png\""), "{html}");
    // A file the report cannot show is refused by name.
    let npy = tmp.path().join("d.npy");
    std::fs::write(&npy, b"x").unwrap();
    let o = surfcap!(&[
        "report",
        p(&clips[0]),
        "--fps",
        "30",
        "-o",
        p(&out),
        "--include",
        p(&npy),
        "--cache-dir",
        p(&cache)
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains(&format!("--include {}: the report shows", npy.display())), "{}", stderr(&o));
}

/// The colour bars of an SVG: runs of rectangles filled with the heat maps' colour-bar ramp,
/// top to bottom.
fn colour_bars(svg: &str) -> usize {
    let fills: Vec<&str> =
        svg.lines().filter(|l| l.starts_with("<rect")).filter_map(|l| l.split("fill=\"").nth(1)?.get(..7)).collect();
    let bar = surfcap_plot::heat_map::colour_bar_fills();
    fills.windows(bar.len()).filter(|w| *w == bar.as_slice()).count()
}

/// The height in CSS pixels of a page laid out by headless Chromium in a 1280-pixel-wide window.
fn page_height(index: &Path) -> u64 {
    let page = index.with_file_name("measured.html");
    let html = std::fs::read_to_string(index).unwrap().replace(
        "</body>",
        "<script>window.addEventListener('load', () => document.body.setAttribute('data-height', document.documentElement.scrollHeight));</script></body>",
    );
    std::fs::write(&page, html).unwrap();
    let profile = tempfile::tempdir().unwrap();
    let o = Command::new("/usr/bin/chromium")
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--virtual-time-budget=5000", "--window-size=1280,900"])
        .arg(format!("--user-data-dir={}", p(profile.path())))
        .arg("--dump-dom")
        .arg(format!("file://{}", p(&page)))
        .output()
        .expect("/usr/bin/chromium runs");
    assert!(o.status.success(), "{}", stderr(&o));
    let dom = stdout(&o);
    let at = dom.find("data-height=\"").unwrap_or_else(|| panic!("no height measured: {dom}")) + 13;
    dom[at..at + dom[at..].find('"').unwrap()].parse().unwrap()
}

#[test]
fn smg_query_says_the_subjects_unit() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let s = tmp.path().join("m.subject");
    let bvh = data.join("cmu_bvh/16_15.bvh");
    let o = surfcap!(&["--quiet", "make", "mannequin", "--bvh", p(&bvh), "--vertices", "1000", "-o", p(&s)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let cache = tmp.path().join("cache");
    let args = |out: &str| {
        vec![
            "smg".to_string(),
            "query".into(),
            p(&s).into(),
            "--connect".into(),
            "16_15:16_15".into(),
            "--from".into(),
            "16_15:0".into(),
            "--to".into(),
            "16_15:60".into(),
            "--distance".into(),
            "3".into(),
            "--time".into(),
            "4".into(),
            "--cache-dir".into(),
            p(&cache).into(),
            "-o".into(),
            p(&tmp.path().join(out)).into(),
        ]
    };
    let a = args("q.glb");
    let o = surfcap!(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    let text = format!("{}{}", stdout(&o), stderr(&o));
    assert!(text.contains(" m covered (asked 3 in 4 s"), "{text}");
    assert!(!text.contains("units"), "{text}");
    let mut a = args("q2.glb");
    a.insert(0, "--json".into());
    let o = surfcap!(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["unit"], "m", "{v}");
    assert!(v["constraints"].as_array().unwrap().iter().any(|c| c["unit"] == "m"), "{v}");
}

#[test]
fn report_heat_maps_carry_colour_bars_and_the_page_stays_short() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let cat = data.join("walking_cat_depraz");
    let cache = tmp.path().join("cache");
    let o = surfcap!(&[
        "--quiet",
        "distance",
        p(&cat),
        "--fps",
        "30",
        "-o",
        p(&tmp.path().join("d.npy")),
        "--cache-dir",
        p(&cache)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A transition's DTW heat map, and six animations with their per-frame path errors.
    let plots = tmp.path().join("plots");
    std::fs::create_dir(&plots).unwrap();
    let (from, to) = ("walk:3", "walk:25");
    let t = plots.join("t.glb");
    let o = surfcap!(&[
        "--quiet",
        "transition",
        p(&cat),
        "--fps",
        "30",
        "--from",
        from,
        "--to",
        to,
        "-o",
        p(&t),
        "--cache-dir",
        p(&cache)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::remove_file(&t).unwrap();
    std::fs::remove_file(plots.join("t.transition.json")).ok();
    let anims = tmp.path().join("anims");
    std::fs::create_dir(&anims).unwrap();
    let blend = anims.join("walk-0.glb");
    let o = surfcap!(&[
        "--quiet",
        "interpolate",
        p(&cat),
        "--fps",
        "30",
        "--from",
        from,
        "--to",
        to,
        "--steps",
        "5",
        "-o",
        p(&blend)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for k in 0..6 {
        let glb = anims.join(format!("walk-{k}.glb"));
        if k > 0 {
            std::fs::copy(&blend, &glb).unwrap();
        }
        let errors: Vec<f64> = (0..5).map(|f| 0.01 * (f + k) as f64).collect();
        let report = serde_json::json!({ "mean_error": 0.02, "per_frame": { "error": errors } });
        std::fs::write(anims.join(format!("walk-{k}.report.json")), report.to_string()).unwrap();
    }
    let out = tmp.path().join("report");
    let o = surfcap!(&[
        "report",
        p(&cat),
        "--fps",
        "30",
        "-o",
        p(&out),
        "--include",
        p(&plots),
        "--include",
        p(&anims),
        "--cache-dir",
        p(&cache)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    // Every heat map on the page (the distance matrix, the transition's warp) has its colour
    // bar, named by what its colours stand for.
    for heat in ["plots/distances.svg", "plots/t-dtw.svg"] {
        assert!(html.contains(&format!("\"{heat}\"")), "{heat}: {html}");
        let svg = std::fs::read_to_string(out.join(heat)).unwrap();
        assert_eq!(colour_bars(&svg), 1, "{heat}");
        assert!(svg.contains("distance"), "{heat}: the bar's name");
    }
    // The six animations' errors share one chart, one line each.
    let chart = std::fs::read_to_string(out.join("plots/path-errors.svg")).unwrap();
    for k in 0..6 {
        assert!(chart.contains(&format!("walk-{k}.glb")), "{k}");
    }
    assert_eq!(html.matches("<img").count(), 3, "two heat maps and the shared error chart: {html}");
    // Laid out in a 1280-pixel window, the page is a few screens, not six stacked plots.
    let height = page_height(&out.join("index.html"));
    assert!(height < 3000, "the report is {height} px tall");
}
