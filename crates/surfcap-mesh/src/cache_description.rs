//! The description file of a cache folder (`subject.json` of the subject cache, `frameset.json`
//! of the frame-set cache): read as a regular file, parsed, and checked to be of the format and
//! version this surfcap writes, with errors naming the file (and the line of a syntax error).

use std::path::Path;

use serde::de::DeserializeOwned;

use crate::error::{Result, err};
use crate::regular_file::read_regular_file;

/// Reads the description at `path` (`what` it is, e.g. "subject description"), which must state
/// the format name `format` and the version `version` (`format_version` reads them from the
/// parsed file): a syntax error names its line, another format or version says to re-import.
pub(crate) fn read_description<H: DeserializeOwned>(
    path: &Path,
    what: &str,
    (format, version): (&str, u32),
    format_version: impl Fn(&H) -> (&str, u32),
) -> Result<H> {
    let text = read_regular_file(path)?;
    let h: H = serde_json::from_slice(&text)
        .map_err(|e| err!(Syntax, "not a surfcap {what}: {e}").in_file(path).at_line(e.line()))?;
    let (found, found_version) = format_version(&h);
    if found != format || found_version != version {
        return Err(err!(
            Unsupported,
            "format {found:?} version {found_version}: expected {format:?} version {version} (re-import the data \
             with this surfcap)"
        )
        .in_file(path));
    }
    Ok(h)
}
