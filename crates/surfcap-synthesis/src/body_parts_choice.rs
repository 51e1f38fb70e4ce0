//! A subject's body parts as the runs that learn per part take them (transfer training,
//! variation training): the user's parts file (any form docs/formats.md, "Body parts files",
//! describes), one part for the whole body, or five parts proposed from the subject (thesis
//! 5.4.2 and 6.4.2: P = 5), as `surfcap parts propose` does. Front ends show the notes.

use std::path::Path;

use surfcap_mesh::Subject;
use surfcap_transfer::BodyParts;
use surfcap_transfer::body_parts_file::{DEFAULT_OVERLAP_RINGS, read_parts_file};
use surfcap_transfer::body_parts_proposal::{Method as ProposalMethod, propose};

use crate::error::{Error, Result};

/// The body parts of `s` and the notes made choosing them: read from `path`, the whole body with
/// `whole_body`, else five proposed parts (with a note naming `option`, the front end's parts
/// option). `who` names the subject in messages ("source", "target", or "" for a run's only
/// subject).
pub fn parts_of(
    path: Option<&Path>,
    whole_body: bool,
    s: &Subject,
    who: &str,
    option: &str,
) -> Result<(BodyParts, Vec<String>)> {
    let subject = if who.is_empty() { "the subject".to_string() } else { format!("the {who} subject") };
    let mut notes = Vec::new();
    let parts = match path {
        Some(p) => read_parts_file(p, s.topology(), s.frame(0).unwrap_or_default())
            .map_err(|e| Error::Request(format!("{e} ({subject} {:?})", s.name)))?,
        None if whole_body => BodyParts::whole_body(s.topology().n_vertices()),
        None => {
            let (parts, report) = propose(s, ProposalMethod::Auto, 5, DEFAULT_OVERLAP_RINGS)?;
            notes.extend(report.notes.iter().cloned());
            let prefix = if who.is_empty() { String::new() } else { format!("{who} ") };
            notes.push(format!(
                "{prefix}{:?}: no {option} given, so 5 parts were proposed from its {} ({}); `surfcap parts propose` writes them to a file you can edit",
                s.name,
                report.method.as_str(),
                parts.names().join(", ")
            ));
            parts
        }
    };
    parts.check_fits(s.topology()).map_err(|e| {
        let file = path.map_or_else(|| "the parts".to_string(), |p| p.display().to_string());
        Error::Request(format!("{file} for {subject} {:?}: {e}", s.name))
    })?;
    Ok((parts, notes))
}
