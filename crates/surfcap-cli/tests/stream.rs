//! The compact stream (`--format stream`, `surfcap eval stream`) on real captures: the file
//! decodes within its grid's error, the viewer's JavaScript decoder (run by Node) gives the Rust
//! decoder's bits exactly, a target error picks the bits, it is several times smaller than glb
//! morph targets, and a damaged file is refused naming the file and what is wrong.

use std::path::Path;

use serde_json::Value;
use surfcap_testkit::{p, stderr, surfcap};

fn json(o: &std::process::Output) -> Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stdout)))
}

/// Decodes `file` with tools/stream-decode-test.mjs; returns the bytes it wrote.
fn node_decode(file: &Path, out: &Path) -> Vec<u8> {
    let root = surfcap_testkit::workspace_root();
    let o = std::process::Command::new("node")
        .arg(root.join("tools/stream-decode-test.mjs"))
        .arg(file)
        .arg(out)
        .output()
        .expect("node runs (install Node.js)");
    assert!(o.status.success(), "the JavaScript decoder failed:\n{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read(out).unwrap()
}

#[test]
fn a_capture_streams_within_its_error_and_the_javascript_decoder_matches_bit_for_bit() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let crane = data.join("vlasic2008/crane");
    let subject = d.path().join("crane.subject");
    let o = surfcap!(&["--quiet", "import", p(&crane), "-o", p(&subject)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = d.path().join("crane.scstream");
    let o = surfcap!(&["--quiet", "export", p(&subject), "--format", "stream", "-o", p(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let source = surfcap_mesh::cache::read_cache(&subject, &surfcap_mesh::NoProgress).unwrap();
    let back = surfcap_formats::stream::read_stream(&out).unwrap();
    assert_eq!(back.topology().triangles(), source.topology().triangles());
    assert_eq!((back.fps, back.up_axis, &back.units), (source.fps, source.up_axis, &source.units));
    assert_eq!(back.sequences()[0].labels, source.sequences()[0].labels);
    // Every vertex within half a grid cell's diagonal of the source, 16 bits over the box.
    let bytes = std::fs::read(&out).unwrap();
    let file = surfcap_formats::stream::StreamFile::parse(&bytes).unwrap();
    let bound = file.quantiser().max_error();
    assert_eq!(file.header.bits, 16);
    let (a, b) = (source.sequences()[0].positions(), back.sequences()[0].positions());
    assert_eq!(a.len(), b.len());
    let worst = a
        .chunks_exact(3)
        .zip(b.chunks_exact(3))
        .map(|(x, y)| (0..3).map(|k| f64::from(x[k] - y[k]).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    assert!(worst <= bound * 1.0001 && worst > 0.0, "error {worst} against the bound {bound}");

    // The JavaScript decoder: same triangles, same bits in every frame.
    let js = node_decode(&out, &d.path().join("js.bin"));
    let mut rust: Vec<u8> = file.triangles.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    rust.extend(file.decode().unwrap().iter().flat_map(|v| v.to_le_bytes()));
    assert_eq!(js.len(), rust.len(), "JavaScript decoded {} bytes, Rust {}", js.len(), rust.len());
    assert!(js == rust, "the JavaScript decoder differs from the Rust decoder");

    // The evaluation: bytes per frame, Mbps, error in % of height; far smaller than glb.
    let r = json(&surfcap!(&["--json", "eval", "stream", p(&subject)]));
    assert_eq!(r["frames"], 175);
    assert_eq!(r["bytes"].as_u64().unwrap() as usize, bytes.len(), "eval codes what export writes");
    let per_frame = r["bytes_per_frame"].as_f64().unwrap();
    assert!((per_frame - bytes.len() as f64 / 175.0).abs() < 1e-9);
    assert!((r["mbps_at_30_fps"].as_f64().unwrap() - per_frame * 8.0 * 30.0 / 1e6).abs() < 1e-9);
    // A noisy capture at 16 bits: about a third of glb (docs/results/stream.md).
    assert!(r["glb_bytes_per_frame"].as_f64().unwrap() > 2.5 * per_frame, "{r}");
    assert_eq!(r["max_error"].as_f64().unwrap(), worst);
    let pct = r["max_error_percent_of_height"].as_f64().unwrap();
    assert!(pct > 0.0 && pct < 0.01, "16 bits: under a ten-thousandth of the height, got {pct}%");
    assert_eq!(r["unit"], "m");
}

#[test]
fn a_target_error_picks_the_bits_and_fewer_bits_make_a_smaller_stream() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let knight = data.join("kaykit_adventurers/knight_Walking_A");
    let fine = json(&surfcap!(&["--json", "eval", "stream", p(&knight)]));
    let coarse = json(&surfcap!(&["--json", "eval", "stream", p(&knight), "--stream-error", "0.1"]));
    assert!(coarse["bits"].as_u64().unwrap() < 16, "{coarse}");
    assert!(coarse["max_error_percent_of_height"].as_f64().unwrap() <= 0.1);
    assert!(coarse["bytes"].as_u64() < fine["bytes"].as_u64());
    // Key frames every frame: each decodes on its own, and costs more.
    let keys = json(&surfcap!(&["--json", "eval", "stream", p(&knight), "--stream-key-interval", "1"]));
    assert_eq!(keys["key_frames"], keys["frames"]);
    assert!(keys["bytes"].as_u64() > fine["bytes"].as_u64());
    assert_eq!(keys["max_error"], fine["max_error"], "the same grid whatever the prediction");
}

#[test]
fn a_damaged_stream_is_refused_naming_the_file_and_the_problem() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("knight.scstream");
    let o = surfcap!(&[
        "--quiet",
        "export",
        p(&data.join("kaykit_adventurers/knight_Walking_A")),
        "--format",
        "stream",
        "-o",
        p(&out)
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&out).unwrap();
    let cut = d.path().join("cut.scstream");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = surfcap_formats::stream::read_stream(&cut).unwrap_err().to_string();
    assert!(e.contains("cut.scstream") && e.contains("the stream ends"), "{e}");
    // Damage inside the last frame's deflated residuals: the frame is named.
    let mut bad = bytes.clone();
    let n = bad.len();
    bad[n - 3] ^= 0xff;
    bad[n - 4] ^= 0xff;
    let broken = d.path().join("broken.scstream");
    std::fs::write(&broken, &bad).unwrap();
    let e = surfcap_formats::stream::read_stream(&broken).unwrap_err().to_string();
    assert!(e.contains("broken.scstream") && e.contains("knight_Walking_A:32"), "{e}");
}
