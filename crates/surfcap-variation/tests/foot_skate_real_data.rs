//! The foot-skate clean-up on real motion: variants of the 1,000-vertex mannequin driven by
//! CMU 16_15 (a walk, real travel), one sequence, short GPDM fits, judged by the shared
//! foot-sliding measure against the capture.

use surfcap_builtin::bvh::read_bvh;
use surfcap_builtin::mannequin::{BodyShape, mannequin};
use surfcap_builtin::mannequin_subject::{Clip, mannequin_subject};
use surfcap_geometry::ground_contacts::{ContactParams, ground_contacts};
use surfcap_geometry::shape_distortion::edge_length_distortion;
use surfcap_mesh::NoProgress;
use surfcap_transfer::body_parts_proposal::{Method, propose};
use surfcap_variation::VariationModel;
use surfcap_variation::variation_model::TrainOptions;
use surfcap_variation::variation_sampling::{SamplingOptions, sample_variants};

fn sliding(frames: &[&[f32]], up: surfcap_mesh::UpAxis) -> f64 {
    let nv = frames[0].len() / 3;
    let flat: Vec<f32> = frames.iter().flat_map(|f| f.iter().copied()).collect();
    let p = ContactParams::default();
    let c = ground_contacts(&flat, nv, 30.0, up, &p);
    surfcap_geometry::foot_sliding::foot_sliding(&flat, nv, 30.0, up, &c, &p, &[]).unwrap().mean_speed
}

#[test]
fn cleaned_variants_of_a_cmu_walk_slide_no_more_than_the_capture_and_keep_their_edges() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let m = mannequin(&BodyShape::average(), 1000).unwrap();
    let path = data.join("cmu_bvh").join("16_15.bvh");
    let bvh = read_bvh(&path).unwrap();
    let clip = Clip::from_bvh(&path, &bvh, &m, bvh.guess_metres_per_unit().0).unwrap();
    let s = mannequin_subject("cmu", &m, &[clip], 30.0).unwrap();
    let (parts, _) = propose(&s, Method::Auto, 5, 2).unwrap();
    let mut train = TrainOptions::default();
    train.gpdm.lbfgs.max_iters = 40;
    train.gpdm.lbfgs.max_evals = 50;
    let model = VariationModel::train(&s, &[0], &parts, &train, &NoProgress).unwrap();
    let walk = &s.sequences()[0];
    let source: Vec<&[f32]> = (0..walk.n_frames()).map(|f| walk.frame(f)).collect();
    let captured = sliding(&source, s.up_axis);
    let rest = &model.reference_pose;
    let edges = |frames: &[&[f32]]| {
        frames.iter().map(|p| edge_length_distortion(s.topology(), rest, rest, p, 0.0)).sum::<f64>()
            / frames.len() as f64
    };
    let captured_edges = edges(&source);
    let (variants, _) = sample_variants(&model, &walk.name, 3, 0, &SamplingOptions::default()).unwrap();
    for (k, v) in variants.iter().enumerate() {
        let before: Vec<&[f32]> =
            v.before_cleanup.as_ref().expect("cleaned by default").iter().map(Vec::as_slice).collect();
        let after: Vec<&[f32]> = v.world.iter().map(Vec::as_slice).collect();
        let (b, a) = (sliding(&before, s.up_axis), sliding(&after, s.up_axis));
        let r = v.cleanup.expect("a report");
        eprintln!("variant {k}: sliding {b:.3} -> {a:.3} m/s (capture {captured:.3}), {r:?}");
        assert!(b > 1.1 * captured, "variant {k}: sampled, it skates ({b} against {captured})");
        assert!(a <= 1.1 * captured, "variant {k}: cleaned, it slides {a} m/s against the capture's {captured}");
        // The pins are real: the planted vertices stay within 2 cm of their pins on average.
        assert!(r.pinned_drift_after < 0.02 && r.pinned_drift_after < 0.25 * r.pinned_drift_before, "{r:?}");
        // The legs bend with little stretching: the clean-up adds less than 15% of the
        // capture's edge distortion to the variant's. Measured on 0.0185: 0.0007-0.0008 by
        // default (every planted vertex pinned at its plant's middle frame, the legs bent as
        // rigidly as possible; the sampled poses, with the learnt motion's stretch, at
        // 0.0185-0.0186); before those two changes 0.0019 on poses at 0.0190-0.0193; with
        // the pins carried by the body (`FootSkateParams::carry_pins`, off by default because
        // the body then drifts off its path) 0.0005-0.0007; `eval vary` judges criterion
        // (iii) on the cleaned frames of its longer fits.
        let (e0, e) = (edges(&before), edges(&after));
        eprintln!("edges: capture {captured_edges:.4}, variant before {e0:.4}, after {e:.4}");
        assert!(e <= e0 + 0.15 * captured_edges, "variant {k}: edge distortion {e0} -> {e} (capture {captured_edges})");
    }
    // With the hips held (`move_root` off, `--hold-hips`): the same samples, the planted feet
    // still pinned, and the legs stretched more than with the root moved (by default the whole
    // body follows a planted foot instead of the leg reaching for it).
    let held_opts = SamplingOptions { move_root: false, ..SamplingOptions::default() };
    let (held, _) = sample_variants(&model, &walk.name, 3, 0, &held_opts).unwrap();
    for (k, (m, h)) in variants.iter().zip(&held).enumerate() {
        assert_eq!(h.before_cleanup, m.before_cleanup, "variant {k}: the same samples");
        let r = h.cleanup.expect("a report");
        assert!(r.pinned_drift_after < 0.02 && r.pinned_drift_after < 0.25 * r.pinned_drift_before, "{r:?}");
        let (e_held, e_moved) = (
            edges(&h.world.iter().map(Vec::as_slice).collect::<Vec<_>>()),
            edges(&m.world.iter().map(Vec::as_slice).collect::<Vec<_>>()),
        );
        eprintln!(
            "variant {k}, hips held: sliding {:.3} m/s, edges {e_held:.4} (root moved {e_moved:.4})",
            r.sliding_after
        );
        assert!(e_moved < e_held, "variant {k}: edges {e_moved} with the root moved, {e_held} with the hips held");
    }
}
