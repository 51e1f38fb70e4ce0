//! What USD's binary crate format (`.usdc`, OpenUSD's `pxr/usd/sdf/crateFile`; not from a paper)
//! says about values, shared by the writer (`usd_crate_write.rs`) and the reader
//! (`usd_crate_read.rs`).
//!
//! A file is an 88-byte bootstrap (`PXR-USDC`, the version's three bytes, the table of
//! contents' offset), value data, and six sections named in the table of contents: `TOKENS`
//! (every name, NUL-separated, compressed), `STRINGS` (string values as token indices),
//! `FIELDS` (name token and value of each field), `FIELDSETS` (each spec's field indices, ended
//! by `u32::MAX`), `PATHS` (the path tree in depth-first order) and `SPECS` (path, field set and
//! kind of each spec: pseudo-root, prim, attribute...). A value is a 64-bit *value rep*: bit 63
//! array, bit 62 inlined (the value is in the low 48 bits), bit 61 compressed, bits 48-55 the
//! type, bits 0-47 the payload (the inlined value, or the value's offset in the file).
//!
//! surfcap writes version 0.8.0, the version usd-core 26.x writes by default; usd-core 26.x
//! refuses versions before 0.4.0 as obsolete and warns that those before 0.8.0 are deprecated.

/// The crate version surfcap writes.
pub const VERSION: [u8; 3] = [0, 8, 0];

/// Value types (OpenUSD `crateDataTypes.h`); only those surfcap writes or reads.
pub mod ty {
    pub const INT: u8 = 3;
    pub const UINT: u8 = 4;
    pub const INT64: u8 = 5;
    pub const FLOAT: u8 = 8;
    pub const DOUBLE: u8 = 9;
    pub const STRING: u8 = 10;
    pub const TOKEN: u8 = 11;
    pub const MATRIX4D: u8 = 15;
    pub const VEC2F: u8 = 20;
    pub const VEC3F: u8 = 24;
    pub const DICTIONARY: u8 = 31;
    pub const TOKEN_VECTOR: u8 = 41;
    pub const SPECIFIER: u8 = 42;
    pub const VARIABILITY: u8 = 44;
    pub const TIME_SAMPLES: u8 = 46;
    pub const DOUBLE_VECTOR: u8 = 48;
}

/// Spec kinds (`SdfSpecType`).
pub mod spec {
    pub const ATTRIBUTE: u8 = 1;
    pub const PRIM: u8 = 6;
    pub const PSEUDO_ROOT: u8 = 7;
}

const ARRAY_BIT: u64 = 1 << 63;
const INLINED_BIT: u64 = 1 << 62;
const COMPRESSED_BIT: u64 = 1 << 61;
const PAYLOAD_MASK: u64 = (1 << 48) - 1;

/// A value rep (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ValueRep(pub u64);

impl ValueRep {
    /// A value stored elsewhere in the file, at byte `offset`.
    pub fn at(ty: u8, offset: u64) -> Self {
        ValueRep((u64::from(ty) << 48) | (offset & PAYLOAD_MASK))
    }
    /// An array stored at byte `offset` (its element count first).
    pub fn array_at(ty: u8, offset: u64) -> Self {
        ValueRep(ARRAY_BIT | Self::at(ty, offset).0)
    }
    /// A value held in the rep itself.
    pub fn inlined(ty: u8, payload: u32) -> Self {
        ValueRep(INLINED_BIT | (u64::from(ty) << 48) | u64::from(payload))
    }
    pub fn ty(self) -> u8 {
        (self.0 >> 48) as u8
    }
    pub fn is_array(self) -> bool {
        self.0 & ARRAY_BIT != 0
    }
    pub fn is_inlined(self) -> bool {
        self.0 & INLINED_BIT != 0
    }
    pub fn is_compressed(self) -> bool {
        self.0 & COMPRESSED_BIT != 0
    }
    pub fn payload(self) -> u64 {
        self.0 & PAYLOAD_MASK
    }
}
