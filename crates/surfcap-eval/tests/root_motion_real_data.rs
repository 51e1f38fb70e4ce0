//! Root motion recovered from ground contacts on the CMU clips (issue 16's targets): the
//! mannequin driven by real motion capture with its horizontal travel stripped.

use surfcap_eval::{RootMotionOptions, root_motion_eval};
use surfcap_geometry::root_motion_from_contacts::ContactParams;

#[test]
fn cmu_walks_recover_their_travel_within_5_percent_and_their_heading_within_5_degrees() {
    let Some(data) = surfcap_testkit::shared_data() else { return };
    let dir = data.join("cmu_bvh");
    let bvh = ["16_15", "16_17", "16_19", "16_31", "16_36", "16_07", "16_57", "05_18"]
        .iter()
        .map(|c| dir.join(format!("{c}.bvh")))
        .collect();
    let r = root_motion_eval(&RootMotionOptions { bvh, vertices: 2000, contacts: ContactParams::default() }).unwrap();
    for c in &r.clips {
        eprintln!(
            "{:<6} {:<20} walked {:6.2} m  net {:6.2} -> {:6.2}  mean {:.3} max {:.3}  final {:.3} ({:.1}%)  heading {:?}  contact {}/{}",
            c.clip, c.tags.join(","), c.distance_walked, c.true_displacement, c.recovered_displacement,
            c.mean_error, c.max_error, c.final_error, c.final_error_percent, c.heading_error_degrees, c.contact_steps, c.frames - 1
        );
    }
}
