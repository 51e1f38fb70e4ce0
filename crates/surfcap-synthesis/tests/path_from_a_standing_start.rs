//! Path following from a frame that stands: the procedural mannequin's idle frames have no
//! direction of travel, only a few millimetres of sway. Placed by aligning that sway with the
//! curve, a walk from any idle frame went off at an angle (5.5-7.1 m mean error on a 10 m line,
//! `surfcap synth path --start idle:K`); tried at every heading, it follows the line.

mod common;

use common::prepared;
use surfcap_builtin::locomotion::Gait as Procedural;
use surfcap_mesh::NoProgress;
use surfcap_motion::path_following::{Curve, PathSearch};
use surfcap_synthesis::{Output, PathQuery, Tolerances};

#[test]
fn a_walk_from_a_standing_frame_follows_a_straight_line() {
    let prep = prepared(&[Procedural::Walk, Procedural::Jog, Procedural::Idle]);
    let s = prep.subject();
    let idle = s.sequences().iter().position(|q| q.name == "idle").expect("an idle clip");
    let (iu, iv, _) = surfcap_geometry::motion_plane_alignment::plane_axes(s.up_axis);
    let mut end = [0.0; 3];
    end[iu] = 10.0;
    let curve = Curve::new(vec![[0.0; 3], end], vec![iu, iv]).unwrap();
    let out = Output::in_memory(Tolerances::default());
    for k in [0, 25, 50] {
        let start = (s.frame_index().range(idle).start + k) as u32;
        let search = PathSearch::for_clips(s.fps, None);
        let q = PathQuery { curve: &curve, restrictions: &[], start: Some(start), search };
        let o = prep.follow_path(&q, &out, &NoProgress).unwrap();
        assert!(o.mean_error < 0.1, "from idle:{k}: mean error {:.3} m on a 10 m line", o.mean_error);
        assert_eq!(o.report.walk.walk[0], start);
    }
}
