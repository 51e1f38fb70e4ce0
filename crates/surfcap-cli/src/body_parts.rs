//! A subject's body parts as the commands that learn per part take them (`transfer train`,
//! `vary train`): `surfcap_transfer::body_parts_choice` (a parts file, the whole body, or five
//! proposed parts), its notes printed as the command's notes.

use std::path::Path;

use surfcap_mesh::Subject;
use surfcap_transfer::BodyParts;
use surfcap_transfer::body_parts_choice::choose_parts;

/// Notes of the parts choice, printed as `note:` lines (`ctx.note`).
struct Notes<'a>(&'a crate::Ctx);

impl surfcap_mesh::Progress for Notes<'_> {
    fn note(&self, text: &str) {
        self.0.note(text);
    }
}

/// The body parts of `s` (`surfcap_transfer::body_parts_choice::choose_parts`), its notes shown.
pub fn parts_of(
    ctx: &crate::Ctx,
    path: Option<&Path>,
    whole_body: bool,
    s: &Subject,
    who: &str,
    option: &str,
) -> anyhow::Result<BodyParts> {
    Ok(choose_parts(path, whole_body, s, who, option, &Notes(ctx))?)
}
