//! Which animation frames a render at its own frame rate shows: output frame `k` is shown at
//! time `k / fps_out` after the first frame, and shows the animation frame nearest that time at
//! the animation's rate `fps_in` (ties to the later frame). So the render plays at the
//! animation's speed whatever its rate: a 120 fps capture rendered at 30 fps shows every fourth
//! frame, a 25 fps one rendered at 50 fps shows each frame twice, and equal rates show every
//! frame once.

/// The animation frames (between `first` and `last`, inclusive) shown by a render at `fps_out`
/// frames per second of an animation playing at `fps_in`: as many as fit in the span's
/// duration `(last - first) / fps_in` (plus the first), never past `last`.
pub fn sample_frames(first: usize, last: usize, fps_in: f64, fps_out: f64) -> Vec<usize> {
    if last < first || !(fps_in > 0.0 && fps_out > 0.0) {
        return Vec::new();
    }
    let span = (last - first) as f64 / fps_in;
    // A small tolerance so that 1/3-second steps land on the last frame despite rounding.
    let n = (span * fps_out + 1e-9).floor() as usize + 1;
    (0..n)
        .map(|k| {
            let t = k as f64 / fps_out;
            (first + (t * fps_in + 0.5 + 1e-9).floor() as usize).min(last)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::sample_frames;

    #[test]
    fn equal_rates_show_every_frame_once() {
        assert_eq!(sample_frames(3, 7, 30.0, 30.0), vec![3, 4, 5, 6, 7]);
        assert_eq!(sample_frames(0, 0, 25.0, 25.0), vec![0]);
    }

    #[test]
    fn a_lower_rate_skips_frames_and_keeps_the_speed() {
        // 120 fps shown at 30 fps: every fourth frame, 1 s of animation in 1 s of render.
        let f = sample_frames(0, 120, 120.0, 30.0);
        assert_eq!(f.len(), 31);
        assert!(f.iter().enumerate().all(|(k, &x)| x == 4 * k), "{f:?}");
        // 25 fps shown at 10 fps: frames nearest 0, 0.1, 0.2 s... (2.5 frames apart).
        assert_eq!(sample_frames(0, 10, 25.0, 10.0), vec![0, 3, 5, 8, 10]);
    }

    #[test]
    fn a_higher_rate_repeats_frames() {
        assert_eq!(sample_frames(0, 2, 25.0, 50.0), vec![0, 1, 1, 2, 2]);
        assert_eq!(sample_frames(10, 12, 30.0, 60.0).len(), 5);
    }

    #[test]
    fn nothing_for_an_empty_span_or_a_bad_rate() {
        assert!(sample_frames(5, 4, 30.0, 30.0).is_empty());
        assert!(sample_frames(0, 4, 0.0, 30.0).is_empty());
        assert!(sample_frames(0, 4, 30.0, f64::NAN).is_empty());
    }
}
