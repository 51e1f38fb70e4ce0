//! `surfcap render` end to end on a real capture (Vlasic crane): the viewer's scene rendered in
//! headless Chromium to an animated GIF, an MP4 video and a folder of PNG frames, each read back
//! (frame count, size, rate, and consecutive frames that differ since the actor moves); a
//! missing Chromium and a folder surfcap did not write are refused with clear messages.

use std::io::Cursor;

use surfcap_testkit::{p, stderr, surfcap};

/// Pixels whose colour differs by more than 30 in some channel between two RGB(A) pictures
/// with `channels` bytes a pixel.
fn changed_pixels(a: &[u8], b: &[u8], channels: usize) -> usize {
    assert_eq!(a.len(), b.len());
    a.chunks_exact(channels)
        .zip(b.chunks_exact(channels))
        .filter(|(x, y)| (0..3).any(|c| x[c].abs_diff(y[c]) > 30))
        .count()
}

/// Pixels that are not the page's background (#f4f4f2) nor near it: the drawn scene.
fn drawn_pixels(rgb: &[u8], channels: usize) -> usize {
    rgb.chunks_exact(channels).filter(|x| x[0].abs_diff(0xf4) + x[1].abs_diff(0xf4) + x[2].abs_diff(0xf2) > 40).count()
}

fn crane() -> Option<std::path::PathBuf> {
    Some(surfcap_testkit::shared_data()?.join("vlasic2008/crane"))
}

fn render(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["render", "--json"];
    all.extend_from_slice(args);
    let o = surfcap!(&all);
    assert!(o.status.success(), "surfcap {}: {}", all.join(" "), stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// A GIF at a lower rate than the capture's (30 fps shown at 10: every third frame, played at the
/// capture's speed): the frame count the rate gives, the size asked, a delay of a tenth of a
/// second, a scene drawn on every frame and consecutive frames that differ.
#[test]
fn render_writes_an_animated_gif_at_the_rate_and_size_asked() {
    let Some(crane) = crane() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let gif = tmp.path().join("crane.gif");
    let out = render(&[p(&crane), "-o", p(&gif), "--size", "320x240", "--frames", "0-29", "--fps", "10"]);
    // 29 frames at 30 fps last 0.967 s: 10 frames at 10 fps (0 to 0.9 s).
    assert_eq!(out["frames"], 10, "{out}");
    assert_eq!((out["width"].as_u64(), out["height"].as_u64()), (Some(320), Some(240)));
    assert_eq!(out["animation_fps"], 30.0);
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut d = opts.read_info(std::fs::File::open(&gif).unwrap()).unwrap();
    assert_eq!((d.width(), d.height()), (320, 240));
    let mut frames = Vec::new();
    while let Some(f) = d.read_next_frame().unwrap() {
        assert_eq!((f.width, f.height, f.delay), (320, 240, 10));
        frames.push(f.buffer.to_vec());
    }
    assert_eq!(frames.len(), 10);
    for (k, f) in frames.iter().enumerate() {
        assert!(drawn_pixels(f, 4) > 2000, "frame {k}: only {} pixels drawn", drawn_pixels(f, 4));
    }
    for k in 0..frames.len() - 1 {
        let n = changed_pixels(&frames[k], &frames[k + 1], 4);
        assert!(n > 50, "GIF frames {k} and {} differ in only {n} pixels", k + 1);
    }
}

/// An MP4 at the capture's rate from a top view: one sample per frame, the size and rate asked,
/// a key frame first; decoded (OpenH264), consecutive frames differ.
#[test]
fn render_writes_an_mp4_with_a_sample_per_frame() {
    let Some(crane) = crane() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let mp4_path = tmp.path().join("crane.mp4");
    let out = render(&[p(&crane), "-o", p(&mp4_path), "--size", "320x240", "--frames", "10-21", "--view", "top"]);
    assert_eq!((out["frames"].as_u64(), out["fps"].as_f64()), (Some(12), Some(30.0)), "{out}");
    let bytes = std::fs::read(&mp4_path).unwrap();
    let size = bytes.len() as u64;
    let mut r = mp4::Mp4Reader::read_header(Cursor::new(bytes), size).unwrap();
    let (id, track) = r.tracks().iter().next().map(|(id, t)| (*id, t)).unwrap();
    assert_eq!((track.width(), track.height()), (320, 240));
    assert_eq!(track.sample_count(), 12);
    assert!((track.frame_rate() - 30.0).abs() < 1e-6, "{}", track.frame_rate());
    let sps = track.sequence_parameter_set().unwrap().to_vec();
    let pps = track.picture_parameter_set().unwrap().to_vec();
    let mut decoder = openh264::decoder::Decoder::new().unwrap();
    let mut pictures = Vec::new();
    for s in 1..=12 {
        let sample = r.read_sample(id, s).unwrap().unwrap();
        assert_eq!(sample.is_sync, s == 1, "sample {s}");
        // AVCC (4-byte lengths) back to Annex B (start codes), parameter sets first.
        let mut annex_b = Vec::new();
        if s == 1 {
            for ps in [&sps, &pps] {
                annex_b.extend_from_slice(&[0, 0, 0, 1]);
                annex_b.extend_from_slice(ps);
            }
        }
        let mut at = 0;
        let data = &sample.bytes[..];
        while at + 4 <= data.len() {
            let n = u32::from_be_bytes(data[at..at + 4].try_into().unwrap()) as usize;
            annex_b.extend_from_slice(&[0, 0, 0, 1]);
            annex_b.extend_from_slice(&data[at + 4..at + 4 + n]);
            at += 4 + n;
        }
        let yuv = decoder.decode(&annex_b).unwrap().expect("a picture per sample");
        let mut rgb = vec![0u8; 320 * 240 * 3];
        yuv.write_rgb8(&mut rgb);
        pictures.push(rgb);
    }
    assert!(drawn_pixels(&pictures[0], 3) > 1000, "{} pixels drawn", drawn_pixels(&pictures[0], 3));
    for k in 0..pictures.len() - 1 {
        let n = changed_pixels(&pictures[k], &pictures[k + 1], 3);
        assert!(n > 20, "MP4 frames {k} and {} differ in only {n} pixels", k + 1);
    }
}

/// PNG frames in a folder, numbered in play order; a second render replaces surfcap's own
/// folder, but a folder of the user's is refused untouched.
#[test]
fn render_writes_numbered_png_frames_and_keeps_a_users_folder() {
    let Some(crane) = crane() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("frames");
    let out = render(&[p(&crane), "-o", p(&dir), "--size", "200x150", "--frames", "40-44", "--view", "side"]);
    assert_eq!(out["frames"], 5, "{out}");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".png"))
        .collect();
    names.sort();
    assert_eq!(names, ["00000.png", "00001.png", "00002.png", "00003.png", "00004.png"]);
    let pics: Vec<_> = names.iter().map(|n| image::open(dir.join(n)).unwrap().into_rgba8()).collect();
    for pic in &pics {
        assert_eq!((pic.width(), pic.height()), (200, 150));
    }
    assert!(changed_pixels(pics[0].as_raw(), pics[4].as_raw(), 4) > 20);
    // Again into surfcap's own folder: replaced.
    render(&[p(&crane), "-o", p(&dir), "--size", "200x150", "--frames", "0-1"]);
    assert_eq!(
        std::fs::read_dir(&dir)
            .unwrap()
            .filter(|e| e.as_ref().unwrap().path().extension().is_some_and(|x| x == "png"))
            .count(),
        2
    );
    // A folder of the user's: refused before any work, its file untouched.
    let mine = tmp.path().join("mine");
    std::fs::create_dir(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), "keep").unwrap();
    let o = surfcap!(&["render", p(&crane), "-o", p(&mine), "--frames", "0-1"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("mine"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(mine.join("notes.txt")).unwrap(), "keep");
    assert_eq!(std::fs::read_dir(&mine).unwrap().count(), 1);
}

/// Without Chromium the error says where it looked and what to do; nothing is written.
#[test]
fn a_missing_chromium_is_a_clear_error() {
    let Some(crane) = crane() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let gif = tmp.path().join("out.gif");
    let o = surfcap!(&["render", p(&crane), "-o", p(&gif), "--chromium", "/nonexistent/chromium"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("Chromium not found at /nonexistent/chromium"), "{e}");
    assert!(e.contains("apt-get install chromium") && e.contains("--chromium"), "{e}");
    assert!(!gif.exists() && std::fs::read_dir(tmp.path()).unwrap().count() == 0, "something was written");
    // Bad requests are refused by name before Chromium starts.
    let o = surfcap!(&["render", p(&crane), "-o", p(&tmp.path().join("x.mp4")), "--size", "321x240"]);
    assert!(stderr(&o).contains("even width and height"), "{}", stderr(&o));
    let o = surfcap!(&["render", p(&crane), "-o", p(&tmp.path().join("x.gif")), "--fps", "60"]);
    assert!(stderr(&o).contains("at most 50 frames per second"), "{}", stderr(&o));
    let o = surfcap!(&["render", p(&crane), "-o", p(&tmp.path().join("x.gif")), "--frames", "0-500"]);
    assert!(stderr(&o).contains("the animation has frames 0 to 174"), "{}", stderr(&o));
}
