//! The name a subject gets when the command line gives none: what its sources share. One
//! source gives its own name; several give the longest prefix of their names that ends at a
//! word (`knight_Walking_A` and `knight_Running_A` give `knight`), else the folder they all lie
//! in (`vlasic2008/crane` and `vlasic2008/samba` give `vlasic2008`), else the first one's name.
//! Named after the first source alone, a subject leaked that one clip's name into every output.
//! (A manifest's or a subject cache's own name, when a source has one, wins over this.)

use std::path::{Path, PathBuf};

use super::file_stem;

/// Where a default subject name comes from (`import` says it, so the user knows what to pass
/// to `--name` to change it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NameFrom {
    /// The only source's name.
    OnlySource,
    /// The longest prefix, ending at a word, that every source's name starts with.
    CommonPrefix,
    /// The folder every source lies in.
    ParentFolder,
    /// The first source's name: the sources share neither a prefix nor a folder.
    FirstSource,
}

impl std::fmt::Display for NameFrom {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            NameFrom::OnlySource => "the source's name",
            NameFrom::CommonPrefix => "the prefix the sources' names share",
            NameFrom::ParentFolder => "the folder the sources lie in",
            NameFrom::FirstSource => "the first source's name (the sources share no prefix or folder)",
        })
    }
}

/// The default name of a subject imported from `paths`, and where it comes from (see the
/// module's documentation).
pub fn default_subject_name(paths: &[PathBuf]) -> (String, NameFrom) {
    let stems: Vec<String> = paths.iter().map(|p| file_stem(p)).collect();
    match stems.as_slice() {
        [] => ("subject".into(), NameFrom::FirstSource),
        [one] => (one.clone(), NameFrom::OnlySource),
        [first, ..] => {
            if let Some(prefix) = word_prefix(&stems) {
                (prefix, NameFrom::CommonPrefix)
            } else if let Some(folder) = common_folder(paths) {
                (folder, NameFrom::ParentFolder)
            } else {
                (first.clone(), NameFrom::FirstSource)
            }
        }
    }
}

/// Separators between the words of a name.
fn is_separator(c: char) -> bool {
    matches!(c, '_' | '-' | '.' | ' ')
}

/// The longest prefix of every name that ends at a word (a separator follows it, or it is a
/// whole name), without trailing separators; `None` when it would hold no letter (`16_15` and
/// `16_17` share only the number `16`).
fn word_prefix(names: &[String]) -> Option<String> {
    let first = names.first()?;
    let mut len = first.len();
    for n in &names[1..] {
        len = first
            .char_indices()
            .zip(n.chars())
            .take_while(|((_, a), b)| a == b)
            .map(|((i, a), _)| i + a.len_utf8())
            .last()
            .unwrap_or(0)
            .min(len);
    }
    let shared = &first[..len];
    // Where the shared part ends in a word for every name: at a name's end or a separator.
    let ends_at_word = |n: &String| n.len() == len || n[len..].starts_with(is_separator);
    let cut = if names.iter().all(ends_at_word) { len } else { shared.rfind(is_separator)? };
    let prefix = shared[..cut].trim_end_matches(is_separator);
    prefix.chars().any(char::is_alphabetic).then(|| prefix.to_string())
}

/// The name of the folder every path lies in, when they share one.
fn common_folder(paths: &[PathBuf]) -> Option<String> {
    let parent = |p: &Path| -> Option<PathBuf> {
        let full = std::path::absolute(p).ok()?;
        // `a/b/` and `a/b/.` name the folder b, whose parent is a.
        let full: PathBuf = full.components().collect();
        full.parent().map(Path::to_path_buf)
    };
    let first = parent(&paths[0])?;
    paths[1..].iter().all(|p| parent(p).as_ref() == Some(&first)).then_some(())?;
    first.file_name().map(|n| n.to_string_lossy().into_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn name(paths: &[&str]) -> (String, NameFrom) {
        default_subject_name(&paths.iter().map(PathBuf::from).collect::<Vec<_>>())
    }

    #[test]
    fn several_sources_are_named_after_what_they_share() {
        let kaykit = "data/kaykit_adventurers";
        let knight = name(&[&format!("{kaykit}/knight_Walking_A"), &format!("{kaykit}/knight_Running_A")]);
        assert_eq!(knight, ("knight".to_string(), NameFrom::CommonPrefix));
        // A whole name is a word: `walk` and `walk_fast` share `walk`.
        assert_eq!(name(&["x/walk.glb", "x/walk_fast.glb"]), ("walk".to_string(), NameFrom::CommonPrefix));
        // `crane` and `samba` share no prefix: their folder.
        assert_eq!(
            name(&["data/vlasic2008/crane", "data/vlasic2008/samba/"]),
            ("vlasic2008".to_string(), NameFrom::ParentFolder)
        );
        // A number alone is no name (`16_15`, `16_17`), nor half a word (`walking`, `walks`).
        assert_eq!(name(&["cmu/16_15.bvh", "cmu/16_17.bvh"]), ("cmu".to_string(), NameFrom::ParentFolder));
        assert_eq!(name(&["a/walking", "a/walks"]), ("a".to_string(), NameFrom::ParentFolder));
        // Nothing shared: the first.
        assert_eq!(name(&["a/crane", "b/samba"]), ("crane".to_string(), NameFrom::FirstSource));
        assert_eq!(name(&["a/crane.obj"]), ("crane".to_string(), NameFrom::OnlySource));
    }
}
