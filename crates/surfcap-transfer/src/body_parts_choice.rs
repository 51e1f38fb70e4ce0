//! The body parts a command that learns per part uses (`transfer train`, `vary train`, and
//! their Python bindings): the user's parts file (any form `body_parts_file` reads), one part
//! for the whole body, or five parts proposed from the subject (thesis 5.4.2 and 6.4.2: P = 5)
//! as `surfcap parts propose` does, checked against the subject's template.

use std::path::Path;

use surfcap_mesh::{Progress, Subject};

use crate::BodyParts;
use crate::body_parts_file::{DEFAULT_OVERLAP_RINGS, read_parts_file};
use crate::body_parts_proposal::{Method, propose};
use crate::error::{Error, Result};

/// The body parts of `s`: read from `path`, the whole body with `whole_body`, else five
/// proposed parts (with a note to `progress` naming `option`, the caller's parts option). `who`
/// names the subject in messages ("source", "target", or "" for a command's only subject).
pub fn choose_parts(
    path: Option<&Path>,
    whole_body: bool,
    s: &Subject,
    who: &str,
    option: &str,
    progress: &dyn Progress,
) -> Result<BodyParts> {
    let subject = if who.is_empty() { "the subject".to_string() } else { format!("the {who} subject") };
    let parts = match path {
        Some(p) => read_parts_file(p, s.topology(), s.frame(0).unwrap_or_default())
            .map_err(|e| Error::Invalid(format!("{e} ({subject} {:?})", s.name)))?,
        None if whole_body => BodyParts::whole_body(s.topology().n_vertices()),
        None => {
            let (parts, report) = propose(s, Method::Auto, 5, DEFAULT_OVERLAP_RINGS)?;
            for n in &report.notes {
                progress.note(n);
            }
            let prefix = if who.is_empty() { String::new() } else { format!("{who} ") };
            progress.note(&format!(
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
        Error::Invalid(format!("{file} for {subject} {:?}: {e}", s.name))
    })?;
    Ok(parts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use surfcap_mesh::{NoProgress, Sequence, Topology, Units, UpAxis};

    fn tetra() -> Subject {
        let topology = Topology::new(4, vec![[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]], None).unwrap();
        let p = vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let seq = Sequence::new("still", 4, p).unwrap();
        Subject::new("tetra", topology, vec![seq], 30.0, UpAxis::parse("+y").unwrap(), Units::parse("m")).unwrap()
    }

    #[test]
    fn whole_body_is_one_part_of_every_vertex() {
        let parts = choose_parts(None, true, &tetra(), "", "--parts", &NoProgress).unwrap();
        assert_eq!(parts.names(), vec!["body"]);
    }

    #[test]
    fn a_missing_parts_file_is_named_with_the_subject() {
        let dir = std::env::temp_dir().join(format!("surfcap-parts-choice-{}", std::process::id()));
        let missing = dir.join("no-such-parts.json");
        let e = choose_parts(Some(&missing), false, &tetra(), "source", "--source-parts", &NoProgress).unwrap_err();
        let m = e.to_string();
        assert!(m.contains("no-such-parts.json") && m.contains("(the source subject \"tetra\")"), "{m}");
    }
}
