//! Procedural locomotion on both body shapes: every gait skins cleanly at every frame.

mod common;

use common::assert_clean_skinning;
use surfcap_builtin::locomotion::{Gait, locomotion};
use surfcap_builtin::mannequin::{BodyShape, mannequin};

#[test]
fn every_gait_skins_without_folds_on_both_shapes() {
    for (shape, vertices) in [(BodyShape::average(), 1500), (BodyShape::heavy(), 4000), (BodyShape::slim(), 3000)] {
        let m = mannequin(&shape, vertices).unwrap();
        assert!(m.topology.is_closed_manifold());
        for gait in Gait::ALL {
            for seed in [0, 1] {
                let poses = locomotion(&m.skeleton, gait, 30.0, gait.duration(), seed).unwrap();
                let [p999, largest, _] = assert_clean_skinning(gait.name(), &m, &poses);
                eprintln!(
                    "{} vertices, {} seed {seed}: edge ratio p99.9 {p999:.2}, largest {largest:.2}",
                    m.topology.n_vertices(),
                    gait.name()
                );
            }
        }
    }
}
