//! Every captured frame of a prepared subject as a compact stream (`surfcap_formats::stream`),
//! the bytes a live player sends its page first: a derived product of the subject, kept in the
//! pipeline's derived cache (coding 2,000 frames of 10k vertices takes most of a minute).

use surfcap_formats::stream::{StreamFile, StreamOptions, encode_stream};
use surfcap_mesh::{Error, ErrorKind, NoProgress};

use crate::Prepared;

/// Frames between two key frames of the captured stream.
pub const KEY_INTERVAL: usize = 60;

/// The subject's captured frames coded at `bits` bits (a key frame every [`KEY_INTERVAL`]),
/// from the derived cache when it holds them for this subject, else coded and stored there;
/// the bool says whether they came from the cache. An entry that does not parse as a stream of
/// this subject's frames and vertices is coded again.
pub fn captured_stream(prep: &Prepared, bits: u32) -> Result<(Vec<u8>, bool), Error> {
    let s = prep.subject();
    let options = StreamOptions { bits, max_error: None, key_interval: KEY_INTERVAL };
    let code = || encode_stream(s, &options).0;
    let Some(cache) = prep.pipe.store().cache.as_ref() else { return Ok((code(), false)) };
    let path = cache.path(
        "play-stream",
        &surfcap_mesh::derived_cache::subject_hash(s),
        &format!("v1 bits {bits} key {KEY_INTERVAL}"),
    );
    let (frames, vertices) = (s.n_frames(), s.topology().n_vertices());
    cache.fetch::<u8, Vec<u8>, Error>(
        &path,
        prep.pipe.store().refresh,
        &NoProgress,
        || {
            let bytes = code();
            Ok(surfcap_mesh::npy::NpyArray { shape: vec![bytes.len()], data: bytes })
        },
        |a| {
            let parsed = StreamFile::parse(&a.data)
                .map_err(|e| Error::new(ErrorKind::Syntax, format!("not a compact stream: {e}")))?;
            let n: usize = parsed.header.sequences.iter().map(|q| q.frames).sum();
            if n != frames || parsed.header.vertices != vertices {
                return Err(Error::new(
                    ErrorKind::Syntax,
                    format!(
                        "a stream of {n} frames of {} vertices, expected {frames} of {vertices}",
                        parsed.header.vertices
                    ),
                ));
            }
            Ok(a.data)
        },
    )
}
