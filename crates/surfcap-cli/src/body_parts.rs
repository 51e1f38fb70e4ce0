//! A subject's body parts as the commands that learn per part take them (`transfer train`,
//! `vary train`): the user's parts file (any form docs/formats.md, "Body parts files", describes), one part for
//! the whole body, or five parts proposed from the subject (thesis 5.4.2 and 6.4.2: P = 5), as
//! `surfcap parts propose` does.

use std::path::Path;

use surfcap_mesh::Subject;
use surfcap_transfer::BodyParts;

/// The body parts of `s` (`surfcap_synthesis::body_parts_choice::parts_of`), its notes shown.
pub fn parts_of(
    ctx: &crate::Ctx,
    path: Option<&Path>,
    whole_body: bool,
    s: &Subject,
    who: &str,
    option: &str,
) -> anyhow::Result<BodyParts> {
    let (parts, notes) = surfcap_synthesis::body_parts_choice::parts_of(path, whole_body, s, who, option)?;
    for n in &notes {
        ctx.note(n);
    }
    Ok(parts)
}
