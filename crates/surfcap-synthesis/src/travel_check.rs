//! Path and distance constraints refused on clips that cannot travel: an in-place clip (root
//! pinned, as game clips are authored) loops on the spot whatever the search does, so a curve
//! or a distance asked of such a subject is impossible, and the user is told which clips and how
//! to give them travel (`import --root-motion contacts`).

use surfcap_mesh::Subject;
use surfcap_motion::clip_travel::{ClipTravel, IN_PLACE_HEIGHTS_PER_SECOND, subject_height};

use crate::error::{Result, refuse};
use crate::words::unit_name;

/// Fails when none of the clips `allowed` (all when `None`; else one flag per sequence, as a
/// tag restriction selects them) travels. `travel` is `subject_travel(s)`, computed once by the
/// caller however many constraints it checks. `what` names the constraint in the message.
pub fn require_travel(s: &Subject, travel: &[ClipTravel], what: &str, allowed: Option<&[bool]>) -> Result<()> {
    let chosen: Vec<_> =
        travel.iter().enumerate().filter(|(q, _)| allowed.is_none_or(|a| a[*q])).map(|x| x.1).collect();
    if chosen.is_empty() || chosen.iter().any(|t| !t.in_place) {
        return Ok(());
    }
    let unit = unit_name(&s.units);
    let shown = 10;
    let mut names: Vec<String> = chosen
        .iter()
        .take(shown)
        .map(|t| format!("{} ({:.2} {unit} in {:.1} s)", t.sequence, t.net_displacement, t.duration_seconds))
        .collect();
    if chosen.len() > shown {
        names.push(format!("and {} more", chosen.len() - shown));
    }
    refuse!(
        "{what} needs clips that travel, but every clip {} is in place: {} (net displacement of the centre of mass, \
         first to last frame; in place means under {IN_PLACE_HEIGHTS_PER_SECOND} x the subject's height ({:.2} {unit}) \
         per second). Give in-place locomotion its travel back from the feet's ground contacts: \
         surfcap import <sources> --root-motion contacts -o <subject>",
        if allowed.is_some() { "allowed there" } else { "of the subject" },
        names.join(", "),
        subject_height(s)
    )
}
