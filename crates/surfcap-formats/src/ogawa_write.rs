//! The Ogawa container (Alembic's file format since 1.5), written: a tree of groups and data
//! blocks addressed by absolute file offsets (the layout is the
//! one of the reference library's `Ogawa::OArchive`, read from its source and checked against
//! files it writes):
//!
//! - a 16-byte header: the magic `Ogawa`, a frozen byte (`0xff` once the file is complete), the
//!   format version `0x00 0x01`, then the little-endian u64 offset of the root group;
//! - a data block: its u64 byte count, then the bytes;
//! - a group: its u64 child count, then one u64 per child: a group's offset (0 = empty group),
//!   or a data block's offset with the top bit set (the top bit alone = empty data).
//!
//! Children are written before their parents, so a group is written once all its children are
//! known. The root's offset sits in the header, before everything, and [`write_ogawa`] streams
//! to a plain `Write` (the atomic writer's temporary file, which cannot seek): it runs the
//! caller's emission twice, first counting bytes only (so the root's offset is known), then
//! writing. The emission must therefore be deterministic; the second pass checks that it lands
//! on the same root and fails otherwise rather than write a file that points nowhere. Memory is
//! what the caller holds: nothing is buffered here.
//!
//! The frozen byte is written as `0xff` straight away: the file is written to a temporary and
//! renamed into place only when complete (`atomic.rs`), so a reader never sees a partial file.

use std::io::{self, Write};

const EMPTY_DATA: u64 = 0x8000_0000_0000_0000;

/// A child of a group: where it is and whether it is a group or a data block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Child(u64);

impl Child {
    /// The empty group (offset 0).
    pub const EMPTY_GROUP: Child = Child(0);
    /// The empty data block.
    pub const EMPTY_DATA: Child = Child(EMPTY_DATA);

    /// The group's offset, or `None` for a data block.
    pub fn group_offset(self) -> Option<u64> {
        (self.0 & EMPTY_DATA == 0).then_some(self.0)
    }
}

/// Appends data blocks and groups; a counting pass has no writer.
pub struct OgawaWriter<'a> {
    w: Option<&'a mut dyn Write>,
    pos: u64,
}

impl OgawaWriter<'_> {
    /// Whether bytes are really written (false in the counting pass: a caller can skip work
    /// that only changes the bytes, never their number, such as content digests).
    pub fn writing(&self) -> bool {
        self.w.is_some()
    }

    fn put(&mut self, bytes: &[u8]) -> io::Result<()> {
        if let Some(w) = self.w.as_mut() {
            w.write_all(bytes)?;
        }
        self.pos += bytes.len() as u64;
        Ok(())
    }

    /// A data block made of `parts` one after the other; no bytes at all give the empty data.
    pub fn data(&mut self, parts: &[&[u8]]) -> io::Result<Child> {
        let size: u64 = parts.iter().map(|p| p.len() as u64).sum();
        if size == 0 {
            return Ok(Child::EMPTY_DATA);
        }
        let at = self.pos;
        self.put(&size.to_le_bytes())?;
        for p in parts {
            self.put(p)?;
        }
        Ok(Child(at | EMPTY_DATA))
    }

    /// A group of `children`; none give the empty group.
    pub fn group(&mut self, children: &[Child]) -> io::Result<Child> {
        if children.is_empty() {
            return Ok(Child::EMPTY_GROUP);
        }
        let at = self.pos;
        self.put(&(children.len() as u64).to_le_bytes())?;
        for c in children {
            self.put(&c.0.to_le_bytes())?;
        }
        Ok(Child(at))
    }
}

/// Writes an Ogawa file whose root group is what `emit` returns. `emit` runs twice (see the
/// module documentation) and must emit the same blocks in the same order both times.
pub fn write_ogawa(
    w: &mut dyn Write,
    mut emit: impl FnMut(&mut OgawaWriter<'_>) -> io::Result<Child>,
) -> io::Result<()> {
    let mut counting = OgawaWriter { w: None, pos: 16 };
    let root = emit(&mut counting)?;
    let Some(root_offset) = root.group_offset() else {
        return Err(io::Error::other("the root of an Ogawa file must be a group"));
    };
    let mut header = Vec::with_capacity(16);
    header.extend_from_slice(b"Ogawa");
    header.push(0xff);
    header.extend_from_slice(&[0, 1]);
    header.extend_from_slice(&root_offset.to_le_bytes());
    w.write_all(&header)?;
    let mut writing = OgawaWriter { w: Some(w), pos: 16 };
    let again = emit(&mut writing)?;
    if again != root || writing.pos != counting.pos {
        return Err(io::Error::other(format!(
            "internal error: the Ogawa layout changed between passes (root {} then {}, {} then {} bytes)",
            root.0, again.0, counting.pos, writing.pos
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn u64_at(b: &[u8], at: usize) -> u64 {
        u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
    }

    #[test]
    fn a_tree_is_laid_out_as_the_format_says() {
        let mut out = Vec::new();
        write_ogawa(&mut out, |o| {
            let a = o.data(&[b"ab", b"c"])?;
            let inner = o.group(&[a, Child::EMPTY_DATA])?;
            let none = o.group(&[])?;
            o.group(&[inner, none, Child::EMPTY_DATA])
        })
        .unwrap();
        assert_eq!(&out[..8], b"Ogawa\xff\x00\x01");
        // data "abc" at 16, the inner group at 16 + 8 + 3 = 27, the root at 27 + 8 + 16 = 51.
        assert_eq!(u64_at(&out, 8), 51);
        assert_eq!((u64_at(&out, 16), &out[24..27]), (3, &b"abc"[..]));
        assert_eq!([u64_at(&out, 27), u64_at(&out, 35), u64_at(&out, 43)], [2, 16 | EMPTY_DATA, EMPTY_DATA]);
        assert_eq!([u64_at(&out, 51), u64_at(&out, 59), u64_at(&out, 67), u64_at(&out, 75)], [3, 27, 0, EMPTY_DATA]);
        assert_eq!(out.len(), 83);
    }

    #[test]
    fn an_emission_that_changes_between_passes_is_refused() {
        let mut calls = 0;
        let e = write_ogawa(&mut Vec::new(), |o| {
            calls += 1;
            let d = if calls == 1 { o.data(&[b"a"])? } else { o.data(&[b"ab"])? };
            o.group(&[d])
        })
        .unwrap_err();
        assert!(e.to_string().contains("layout changed"), "{e}");
        let e = write_ogawa(&mut Vec::new(), |o| o.data(&[b"a"])).unwrap_err();
        assert!(e.to_string().contains("must be a group"), "{e}");
    }
}
