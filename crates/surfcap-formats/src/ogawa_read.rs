//! The Ogawa container of Alembic files (for `.abc` import): the binary layer under
//! `abc_read.rs`. Not from the thesis. Written from the format as the reference library
//! (github.com/alembic/alembic, `lib/Alembic/Ogawa/IArchive.cpp`, `IGroup.cpp`, `IData.cpp`,
//! `IStreams.cpp`) reads it, and checked against files that library writes (PyPI `alembic3d`).
//!
//! Layout (all integers little-endian):
//! - a 16-byte header: the magic `Ogawa` (bytes 0-4), the frozen flag (byte 5: `0xff` once the
//!   writer closed the file, `0x00` while it was still writing), the format version as two bytes
//!   `0x00 0x01` (bytes 6-7), and the position of the root group (u64, bytes 8-15);
//! - a *group* at position `p`: a u64 child count `n`, then `n` u64 child entries. An entry with
//!   its top bit set is a *data* block at the position in the other 63 bits, else a group. The
//!   entry `0` is the empty group and `0x8000_0000_0000_0000` the empty data;
//! - a *data* block at position `p`: a u64 byte size `s`, then `s` bytes.
//!
//! Untrusted input: every position and size is checked against the file's length before it is
//! used (nothing is allocated from a number in the file: group entries are only decoded once
//! their table is known to lie inside the file, data blocks are borrowed slices of it). Groups
//! are not recursive here; the Abc layer walks them through [`Ogawa::tree_group`], which refuses
//! a group reached twice (a cycle, or a shared subtree that could blow up exponentially) and a
//! depth over [`MAX_DEPTH`], so a malicious file can neither loop nor overflow the stack. The
//! group tables read in all must also fit in the file once each (they cannot overlap in a file
//! the reference library wrote), which bounds the work by the file's length.
//!
//! Choices where the format leaves room:
//! - A file whose frozen flag is `0x00` is refused: its writer stopped before closing it, so the
//!   root group position and the last samples may be missing (the reference library opens it
//!   and reads whatever is there, which may be silently incomplete).
//! - The HDF5 container of old Alembic files (magic `\x89HDF`) is refused with the conversion
//!   command (`abcconvert -toOgawa`), not read.

use std::cell::{Cell, RefCell};
use std::collections::HashSet;

use surfcap_mesh::error::{Location, Result, err};

/// Deepest group nesting the Abc layer may walk (objects and compound properties). Real files
/// nest a few levels per object; 256 leaves room for deep scene hierarchies.
pub const MAX_DEPTH: usize = 256;

/// The top bit of a child entry: the child is data.
const DATA_BIT: u64 = 1 << 63;

/// A child of a group: a group or a data block, by position (0 for the empty one).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Child {
    Group(u64),
    Data(u64),
}

impl Child {
    fn from_entry(e: u64) -> Child {
        if e & DATA_BIT != 0 { Child::Data(e & !DATA_BIT) } else { Child::Group(e) }
    }

    pub fn is_group(&self) -> bool {
        matches!(self, Child::Group(_))
    }
}

/// An Ogawa file held in memory.
pub struct Ogawa<'a> {
    bytes: &'a [u8],
    /// Position of the root group.
    pub root: u64,
    /// Group table entries still allowed to be read (see the module documentation).
    budget: Cell<u64>,
    visited: RefCell<HashSet<u64>>,
}

fn u64_at(bytes: &[u8], pos: usize) -> u64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&bytes[pos..pos + 8]);
    u64::from_le_bytes(b)
}

impl<'a> Ogawa<'a> {
    /// Checks the header and returns the container (errors carry the byte offset).
    pub fn open(bytes: &'a [u8]) -> Result<Ogawa<'a>> {
        if bytes.starts_with(b"\x89HDF") {
            return Err(err!(
                Unsupported,
                "Alembic file in the old HDF5 container: surfcap reads the current Ogawa container; convert it with `abcconvert -toOgawa input.abc output.abc` (from the Alembic tools) or re-export it from a current DCC tool"
            ));
        }
        if bytes.is_empty() {
            return Err(err!(Empty, "empty file: expected an Alembic (Ogawa) archive"));
        }
        let n = bytes.len().min(5);
        if bytes[..n] != b"Ogawa"[..n] {
            return Err(
                err!(Syntax, "not an Alembic file: expected the magic `Ogawa` at the start").at(Location::Byte(0))
            );
        }
        if bytes.len() < 16 {
            return Err(err!(
                Truncated,
                "the file ends at byte {} inside the 16-byte Ogawa header (magic, frozen flag, version, root group position)",
                bytes.len()
            )
            .at(Location::Byte(bytes.len() as u64)));
        }
        match bytes[5] {
            0xff => {}
            0x00 => {
                return Err(err!(
                    Truncated,
                    "the Ogawa frozen flag is 0x00: the program writing this file stopped before closing it, so it may be incomplete (write it again)"
                )
                .at(Location::Byte(5)));
            }
            f => {
                return Err(
                    err!(Syntax, "Ogawa frozen flag {f:#04x}: expected 0xff (closed) or 0x00").at(Location::Byte(5))
                );
            }
        }
        let version = u16::from_be_bytes([bytes[6], bytes[7]]);
        if version != 1 {
            return Err(err!(Unsupported, "Ogawa version {version}: expected 1").at(Location::Byte(6)));
        }
        let root = u64_at(bytes, 8);
        let o = Ogawa { bytes, root, budget: Cell::new(bytes.len() as u64 / 8), visited: RefCell::new(HashSet::new()) };
        if root == 0 || root & DATA_BIT != 0 {
            return Err(err!(Syntax, "root group position {root:#x}: expected a group").at(Location::Byte(8)));
        }
        Ok(o)
    }

    /// The file's length in bytes.
    pub fn len(&self) -> u64 {
        self.bytes.len() as u64
    }

    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    /// The children of the group at `pos` (none for the empty group 0).
    pub fn group(&self, pos: u64) -> Result<Vec<Child>> {
        if pos == 0 {
            return Ok(Vec::new());
        }
        let len = self.len();
        if pos < 16 || pos.checked_add(8).is_none_or(|e| e > len) {
            return Err(err!(
                Truncated,
                "group at byte {pos}: its child count lies outside the file ({len} bytes, header 0-15)"
            )
            .at(Location::Byte(pos)));
        }
        let n = u64_at(self.bytes, pos as usize);
        let room = (len - pos - 8) / 8;
        if n > room {
            return Err(err!(
                Truncated,
                "group at byte {pos} declares {n} children: the file has room for at most {room} after it"
            )
            .at(Location::Byte(pos)));
        }
        let left = self.budget.get();
        if n > left {
            return Err(err!(
                Syntax,
                "group at byte {pos}: the group tables read so far hold more entries than the file can (tables overlap: the file is damaged or built to loop)"
            )
            .at(Location::Byte(pos)));
        }
        self.budget.set(left - n);
        let start = pos as usize + 8;
        Ok((0..n as usize).map(|i| Child::from_entry(u64_at(self.bytes, start + 8 * i))).collect())
    }

    /// The children of a group of the object/property tree at `depth`: refused when the group
    /// was already walked (a cycle) or the nesting is deeper than [`MAX_DEPTH`].
    pub fn tree_group(&self, pos: u64, depth: usize) -> Result<Vec<Child>> {
        if depth > MAX_DEPTH {
            return Err(err!(
                Unsupported,
                "group at byte {pos} is nested {depth} levels deep: at most {MAX_DEPTH} are read"
            )
            .at(Location::Byte(pos)));
        }
        if pos != 0 && !self.visited.borrow_mut().insert(pos) {
            return Err(err!(
                Syntax,
                "group at byte {pos} is reached a second time: an Alembic file is a tree (the file is damaged or built to loop)"
            )
            .at(Location::Byte(pos)));
        }
        self.group(pos)
    }

    /// The bytes of the data block at `pos` (empty for the empty data 0).
    pub fn data(&self, pos: u64) -> Result<&'a [u8]> {
        if pos == 0 {
            return Ok(&[]);
        }
        let len = self.len();
        if pos < 16 || pos.checked_add(8).is_none_or(|e| e > len) {
            return Err(err!(
                Truncated,
                "data at byte {pos}: its size lies outside the file ({len} bytes, header 0-15)"
            )
            .at(Location::Byte(pos)));
        }
        let size = u64_at(self.bytes, pos as usize);
        let room = len - pos - 8;
        if size > room {
            return Err(err!(
                Truncated,
                "data at byte {pos} declares {size} bytes: the file has {room} after its size field"
            )
            .at(Location::Byte(pos)));
        }
        let start = pos as usize + 8;
        Ok(&self.bytes[start..start + size as usize])
    }

    /// The data of `child`, refused when it is a group (`what` names the expected content).
    pub fn child_data(&self, child: Option<&Child>, what: &str) -> Result<(u64, &'a [u8])> {
        match child {
            Some(Child::Data(p)) => Ok((*p, self.data(*p)?)),
            Some(Child::Group(p)) => {
                Err(err!(Syntax, "{what}: found a group at byte {p}, expected data").at(Location::Byte(*p)))
            }
            None => Err(err!(Syntax, "{what}: missing (the group has too few children)")),
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use surfcap_mesh::error::ErrorKind;

    /// Builds Ogawa files by hand: a header, then blocks appended in order.
    pub(crate) struct Builder {
        pub bytes: Vec<u8>,
    }

    impl Builder {
        pub fn new() -> Self {
            let mut bytes = b"Ogawa\xff\x00\x01".to_vec();
            bytes.extend_from_slice(&0u64.to_le_bytes());
            Builder { bytes }
        }

        pub fn data(&mut self, d: &[u8]) -> u64 {
            if d.is_empty() {
                return DATA_BIT;
            }
            let p = self.bytes.len() as u64;
            self.bytes.extend_from_slice(&(d.len() as u64).to_le_bytes());
            self.bytes.extend_from_slice(d);
            p | DATA_BIT
        }

        pub fn group(&mut self, children: &[u64]) -> u64 {
            if children.is_empty() {
                return 0;
            }
            let p = self.bytes.len() as u64;
            self.bytes.extend_from_slice(&(children.len() as u64).to_le_bytes());
            for c in children {
                self.bytes.extend_from_slice(&c.to_le_bytes());
            }
            p
        }

        pub fn finish(mut self, root: u64) -> Vec<u8> {
            self.bytes[8..16].copy_from_slice(&root.to_le_bytes());
            self.bytes
        }
    }

    fn open_err(bytes: &[u8]) -> surfcap_mesh::error::Error {
        match Ogawa::open(bytes) {
            Ok(_) => panic!("expected an error"),
            Err(e) => e,
        }
    }

    #[test]
    fn groups_and_data_are_read() {
        let mut b = Builder::new();
        let d = b.data(b"hello");
        let inner = b.group(&[d, DATA_BIT]);
        let root = b.group(&[inner, d, 0]);
        let bytes = b.finish(root);
        let o = Ogawa::open(&bytes).unwrap();
        let kids = o.tree_group(o.root, 0).unwrap();
        assert_eq!(kids, [Child::Group(inner), Child::Data(d & !DATA_BIT), Child::Group(0)]);
        assert_eq!(o.data(d & !DATA_BIT).unwrap(), b"hello");
        let inner_kids = o.tree_group(inner, 1).unwrap();
        assert_eq!(o.child_data(inner_kids.get(1), "x").unwrap().1, b"");
        assert!(o.tree_group(0, 1).unwrap().is_empty());
    }

    #[test]
    fn bad_headers_name_the_byte() {
        let e = open_err(b"Ogaw");
        assert_eq!((e.kind, e.location.clone()), (ErrorKind::Truncated, Some(Location::Byte(4))));
        let e = open_err(b"Ogawa\xff\x00\x01\x10");
        assert!(e.to_string().contains("inside the 16-byte Ogawa header"), "{e}");
        let e = open_err(b"\x89HDF\r\n\x1a\n0000000000000000");
        assert_eq!(e.kind, ErrorKind::Unsupported);
        assert!(e.to_string().contains("abcconvert -toOgawa"), "{e}");
        let e = open_err(b"PK\x03\x04 not alembic at all");
        assert!(e.to_string().contains("expected the magic `Ogawa`"), "{e}");
        let mut b = Builder::new().finish(40);
        b[5] = 0;
        let e = open_err(&b);
        assert!(e.to_string().starts_with("byte 5: the Ogawa frozen flag is 0x00"), "{e}");
        b[5] = 0xff;
        b[7] = 2;
        assert!(open_err(&b).to_string().contains("Ogawa version 2: expected 1"));
    }

    #[test]
    fn offsets_past_the_end_and_huge_counts_are_refused() {
        let mut b = Builder::new();
        let g = b.group(&[DATA_BIT | 1000]);
        let bytes = b.finish(g);
        let o = Ogawa::open(&bytes).unwrap();
        let kids = o.tree_group(o.root, 0).unwrap();
        let e = o.child_data(kids.first(), "x").unwrap_err();
        assert_eq!(e.location, Some(Location::Byte(1000)));
        assert!(e.to_string().contains("data at byte 1000: its size lies outside the file (32 bytes"), "{e}");
        // A child count that would need more bytes than the file has.
        let mut bytes = Builder::new().finish(16);
        bytes.extend_from_slice(&u64::MAX.to_le_bytes());
        let o = Ogawa::open(&bytes).unwrap();
        let e = o.group(16).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Truncated);
        assert!(e.to_string().contains("declares 18446744073709551615 children"), "{e}");
        // A data size that overflows the file (and u64 arithmetic).
        let mut bytes = Builder::new().finish(16);
        bytes.extend_from_slice(&(u64::MAX - 3).to_le_bytes());
        let o = Ogawa::open(&bytes).unwrap();
        let e = o.data(16).unwrap_err();
        assert!(e.to_string().contains("declares 18446744073709551612 bytes: the file has 0"), "{e}");
        let e = o.data(u64::MAX >> 1).unwrap_err();
        assert_eq!(e.kind, ErrorKind::Truncated);
    }

    #[test]
    fn cycles_and_deep_nesting_are_refused() {
        // A group that lists itself.
        let mut bytes = Builder::new().finish(16);
        bytes.extend_from_slice(&1u64.to_le_bytes());
        bytes.extend_from_slice(&16u64.to_le_bytes());
        let o = Ogawa::open(&bytes).unwrap();
        let kids = o.tree_group(16, 0).unwrap();
        assert_eq!(kids, [Child::Group(16)]);
        let e = o.tree_group(16, 1).unwrap_err();
        assert!(e.to_string().contains("group at byte 16 is reached a second time"), "{e}");
        let e = o.tree_group(24, MAX_DEPTH + 1).unwrap_err();
        assert!(e.to_string().contains("nested 257 levels deep"), "{e}");
        // Overlapping tables: each group read once, but together more entries than the file holds.
        let mut b = Builder::new();
        let g = b.group(&[0; 8]);
        let bytes = b.finish(g);
        let o = Ogawa::open(&bytes).unwrap();
        o.group(16).unwrap();
        let e = o.group(16).unwrap_err();
        assert!(e.to_string().contains("tables overlap"), "{e}");
    }
}
