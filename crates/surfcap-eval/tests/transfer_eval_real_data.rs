//! The transfer evaluation on the KayKit knight and barbarian (same clips, two bodies).

use surfcap_eval::transfer_eval::{CaseParts, TransferEvalOptions, kaykit_case, transfer_case_eval};

#[test]
fn knight_to_barbarian_learning_curves_fall_and_gp_nn_beats_linear() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let case = kaykit_case(&data, "barbarian", CaseParts::WholeBody).unwrap();
    let opts = TransferEvalOptions { sizes: vec![10, 50, 150], ..TransferEvalOptions::default() };
    let t0 = std::time::Instant::now();
    let r = transfer_case_eval(&case, &opts).unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&r).unwrap());
    eprintln!("{:.1} s", t0.elapsed().as_secs_f64());
    let curve = |m: &str, v: &str| r.curves.iter().find(|c| c.method == m && c.variant == v).unwrap();
    let nn = curve("GP-NN", "random");
    assert_eq!(nn.points.len(), 3);
    assert!(nn.points[2].cv_percent < nn.points[0].cv_percent, "{nn:?}");
    let lin = curve("linear", "random");
    assert!(nn.points[2].cv_percent < lin.points[2].cv_percent, "{nn:?} {lin:?}");
}
