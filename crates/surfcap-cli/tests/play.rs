//! `surfcap play` end to end on the CMU-driven mannequin (subject 16's walks, turns and jog, and
//! subject 113 standing still): the server's routes (the info, the captured frames as a compact stream that
//! the Rust reader decodes, steps refused unless JSON from the page's own origin, a foreign
//! `Host` refused), then the page in headless Chromium (tools/play-page.mjs) steered by scripted
//! key presses: walking right, then up and right (a left turn of 45 degrees), then stopping.
//! The centre track the page keeps must head the commanded way after each and come to rest after
//! the stop, at a measured frame rate, with no console error; a transition the controller chose
//! is then read back from its route as a stream of blended frames, whole and from a frame on.
//! Every blended frame must have been drawn exact or as its stand-in (none late). The same
//! steering is checked on the mannequin `surfcap demo` builds.

use std::process::Command;

use surfcap_testkit::{ViewServer, http_request, http_request_as, p, stderr, surfcap};

/// The difference of two headings, degrees, in -180..180.
fn angle(a: f64, b: f64) -> f64 {
    (a - b + 540.0).rem_euclid(360.0) - 180.0
}

#[test]
fn the_play_page_turns_and_stops_the_character_as_the_keys_ask() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let subject = tmp.path().join("cmu.subject");
    let clips: Vec<String> = [
        "cmu_bvh/16_15",
        "cmu_bvh/16_17",
        "cmu_bvh/16_19",
        "cmu_bvh/16_31",
        "cmu_bvh/16_36",
        "cmu_bvh/16_57",
        "cmu_bvh_loops/113_21",
    ]
    .iter()
    .map(|c| p(&data.join(format!("{c}.bvh"))).to_string())
    .collect();
    let mut args = vec!["make", "mannequin", "--bvh"];
    args.extend(clips.iter().map(String::as_str));
    args.extend(["--vertices", "1500", "-o", p(&subject), "--quiet"]);
    let o = surfcap!(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let cache = tmp.path().join("cache");
    let server =
        ViewServer::start_command(env!("CARGO_BIN_EXE_surfcap"), &["play"], &[p(&subject), "--cache-dir", p(&cache)]);
    let url = server.url.clone();

    // The routes.
    let (status, body) = server.get("/api/play/info");
    assert_eq!(status, 200);
    let info: serde_json::Value = serde_json::from_slice(&body).unwrap();
    let frames = info["frames"].as_u64().unwrap() as usize;
    assert!(frames > 300, "{info}");
    assert_eq!(info["units"], "m");
    assert!(info["gaits"].as_array().unwrap().iter().any(|g| g == "idle"), "{info}");
    let (status, stream) = server.get("/api/play/stream");
    assert_eq!(status, 200);
    assert_eq!(stream.len() as u64, info["stream"]["bytes"].as_u64().unwrap());
    let parsed = surfcap_formats::stream::StreamFile::parse(&stream).unwrap();
    assert_eq!(parsed.header.sequences.iter().map(|s| s.frames).sum::<usize>(), frames);
    assert_eq!(parsed.header.vertices as u64, info["vertices"].as_u64().unwrap());
    assert_eq!(parsed.decode().unwrap().len(), frames * parsed.header.vertices * 3);
    // A step must be JSON (a form post from another page is refused), a foreign Host is refused.
    let (status, body) = http_request(&url, "POST", "/api/play/step");
    assert_eq!(status, 415, "{}", String::from_utf8_lossy(&body));
    let port = url.trim_end_matches('/').rsplit(':').next().unwrap().to_string();
    assert_eq!(http_request_as(&url, "GET", "/api/play/info", &format!("evil.example:{port}")).0, 403);
    assert_eq!(server.get("/api/play/blend/99999").0, 404);
    assert_eq!(server.get("/api/play/nothing").0, 404);

    let seen = steer_and_check(&url, &info);
    assert!(seen["transitions"].as_u64().unwrap() >= 1, "{seen}");
    // A transition chosen is served as a stream of blended frames, decoded by the Rust reader.
    let (status, blend) = server.get("/api/play/blend/0");
    assert_eq!(status, 200);
    let b = surfcap_formats::stream::StreamFile::parse(&blend).unwrap();
    assert_eq!(b.header.vertices, parsed.header.vertices);
    assert!(b.header.sequences[0].frames >= 1 && b.header.sequences[0].name.contains("->"), "{:?}", b.header);
    let whole = b.decode().unwrap();
    assert!(whole.iter().all(|x| x.is_finite()));
    // Piece by piece: the frames from 1 on are the whole stream's from 1 on; none from past the end.
    let total = b.header.sequences[0].frames;
    let per = 3 * b.header.vertices;
    if total > 1 {
        let (status, piece) = server.get("/api/play/blend/0/from/1");
        assert_eq!(status, 200);
        let piece = surfcap_formats::stream::StreamFile::parse(&piece).unwrap().decode().unwrap();
        assert_eq!(piece.len(), (total - 1) * per);
        let step = 1.0f32 / (1 << 15) as f32;
        let far = piece.iter().zip(&whole[per..]).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
        let extent = whole.iter().fold(0.0f32, |m, x| m.max(x.abs()));
        assert!(far <= 4.0 * step * extent.max(1.0), "a piece's frame is {far} from the whole stream's");
    }
    let (status, body) = server.get(&format!("/api/play/blend/0/from/{total}"));
    assert_eq!(status, 404, "{}", String::from_utf8_lossy(&body));
}

/// `surfcap play` on the subject `surfcap demo` builds (the procedural mannequin's walk, jog,
/// turns, jump and idle), with the graph the demo cached: the page steers it as on the CMU
/// subject.
#[test]
fn the_play_page_steers_the_demos_mannequin() {
    let tmp = tempfile::tempdir().unwrap();
    let demo = tmp.path().join("demo");
    let o = surfcap!(&["demo", "-o", p(&demo), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let subject = demo.join("mannequin.subject");
    let cache = demo.join("cache");
    let server =
        ViewServer::start_command(env!("CARGO_BIN_EXE_surfcap"), &["play"], &[p(&subject), "--cache-dir", p(&cache)]);
    let (status, body) = server.get("/api/play/info");
    assert_eq!(status, 200);
    let info: serde_json::Value = serde_json::from_slice(&body).unwrap();
    let gaits: Vec<&str> = info["gaits"].as_array().unwrap().iter().filter_map(|g| g.as_str()).collect();
    assert!(["walk", "run", "idle"].iter().all(|g| gaits.contains(g)), "{info}");
    let seen = steer_and_check(&server.url, &info);
    assert!(seen["blendsShown"].as_u64().unwrap() + seen["standIns"].as_u64().unwrap() >= 1, "{seen}");
}

/// Steers the play page at `url` in headless Chromium (tools/play-page.mjs steer): right, then
/// up and right (a left turn of 45 degrees), then a stop; checks that the centre track heads
/// as asked after each and rests after the stop, at a measured frame rate, and that every
/// blended frame was drawn exact or as its stand-in (none late once the captured frames are
/// decoded). Returns what the page said.
fn steer_and_check(url: &str, info: &serde_json::Value) -> serde_json::Value {
    let tmp = tempfile::tempdir().unwrap();
    let tools = surfcap_testkit::workspace_root().join("tools");
    assert!(tools.join("node_modules/playwright-core").is_dir(), "playwright-core is missing: run scripts/test");
    let shot = tmp.path().join("play.png");
    let o = Command::new("node").arg(tools.join("play-page.mjs")).args([url, "steer", p(&shot)]).output().unwrap();
    assert!(
        o.status.success(),
        "play page failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    let seen: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    eprintln!("{seen}");
    assert!(std::fs::metadata(&shot).unwrap().len() > 1000);
    assert!(seen["firstFrameMs"].as_f64().is_some(), "{seen}");
    let walk = info["walk_speed"].as_f64().unwrap();
    // Right (heading 0), then up and right (heading 45: a left turn), then a stop.
    let right = &seen["right"];
    let up = &seen["up"];
    let stopped = &seen["stopped"];
    assert_eq!((right["commandHeading"].as_f64(), up["commandHeading"].as_f64()), (Some(0.0), Some(45.0)), "{seen}");
    for (s, want) in [(right, 0.0), (up, 45.0)] {
        let heading = s["heading"].as_f64().unwrap_or(f64::NAN);
        assert!(angle(heading, want).abs() < 25.0, "asked heading {want}, the centre track heads {heading}: {seen}");
        let speed = s["speed"].as_f64().unwrap();
        assert!(speed > 0.4 * walk, "asked {walk} m/s, the centre track moves {speed} m/s: {seen}");
    }
    let rest = stopped["speed"].as_f64().unwrap();
    assert!(stopped["commandSpeed"].as_f64() == Some(0.0) && rest < 0.15 * walk, "stopped at {rest} m/s: {seen}");
    // The frame rate is measured (headless Chromium renders in software here; a real GPU runs 60).
    let fps = stopped["fps"].as_f64().unwrap();
    assert!(fps > 5.0, "the page ran at {fps} frames a second: {seen}");
    assert!(seen["transitions"].as_u64().unwrap() >= 1, "{seen}");
    let late = &seen["late"];
    assert_eq!((late["blend"].as_u64(), late["captured"].as_u64()), (Some(0), Some(0)), "late frames: {seen}");
    seen
}
