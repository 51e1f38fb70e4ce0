//! The transfer evaluation on the KayKit knight and barbarian (same clips, two bodies): the
//! goal (GP-NN below Baran et al. on cross-validation error at every training size)
//! and seamless stitching (edges at part boundaries change less than with averaged overlaps).

use surfcap_eval::transfer_eval::{CaseParts, TransferEvalOptions, kaykit_case, transfer_case_eval};

#[test]
fn knight_to_barbarian_gp_nn_beats_baran_at_every_size_and_stitching_leaves_no_seam() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let case = kaykit_case(&data, "barbarian", CaseParts::Proposed { overlap_rings: 2 }).unwrap();
    assert_eq!(case.target_parts.len(), 5);
    let opts = TransferEvalOptions { sizes: vec![10, 50], ..TransferEvalOptions::default() };
    let r = transfer_case_eval(&case, &opts).unwrap();
    let curve = |m: &str, v: &str| r.curves.iter().find(|c| c.method == m && c.variant == v).unwrap();
    let (nn, baran) = (curve("GP-NN", "random"), curve("Baran", "random"));
    for (a, b) in nn.points.iter().zip(&baran.points) {
        assert!(
            a.cv_percent < b.cv_percent,
            "n = {}: GP-NN {:.3}% vs Baran {:.3}%",
            a.size,
            a.cv_percent,
            b.cv_percent
        );
    }
    assert!(nn.points[1].cv_percent < nn.points[0].cv_percent, "more pairs, lower error: {nn:?}");
    assert!(curve("GP-NN", "whole-body").points.len() == 2);
    // Densification of the key pairs recovers the true (identity) frame map.
    assert!(r.densify_frame_error.mean < 0.5, "{:?}", r.densify_frame_error);
    assert_eq!(r.densified_pairs, r.pool_pairs);
    // Stitching: no seam at the part boundaries, no worse than averaging overall.
    let rec = |n: &str| r.reconstruction.iter().find(|x| x.reconstruction == n).unwrap();
    let (avg, stitch) = (rec("average"), rec("stitch"));
    assert!(stitch.boundary_max.unwrap() < 0.1 * avg.boundary_max.unwrap(), "{stitch:?} vs {avg:?}");
    assert!(stitch.rms_percent <= avg.rms_percent, "{stitch:?} vs {avg:?}");
    eprintln!("{}", serde_json::to_string_pretty(&r.reconstruction).unwrap());
}
