//! Columns: the unit of a chunk. Each is `varint count · varint bytes ·
//! bytes`, the bytes coded by meshoptimizer's vertex codec (version 1,
//! level 3: what `MeshoptDecoder.decodeVertexBuffer` of the `meshoptimizer`
//! npm package reads), its index-sequence codec (`decodeIndexSequence`),
//! or raw (the corner-edit bit masks). Also the varint and bit helpers.

use super::types::{invalid, StreamError};

/// Meshoptimizer vertex codec version and level the encoder uses.
const VERTEX_VERSION: i32 = 1;
const VERTEX_LEVEL: i32 = 3;

pub(super) fn put_varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}

/// Element types a vertex column may hold (size a multiple of 4, at most
/// 256 bytes), as little-endian bytes.
pub(super) trait Element: Copy + Default {
    fn write(&self, out: &mut Vec<u8>);
    fn read(bytes: &[u8]) -> Self;
}

impl Element for u32 {
    fn write(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    fn read(b: &[u8]) -> Self {
        u32::from_le_bytes([b[0], b[1], b[2], b[3]])
    }
}

impl Element for [u16; 4] {
    fn write(&self, out: &mut Vec<u8>) {
        for v in self {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    fn read(b: &[u8]) -> Self {
        [0, 1, 2, 3].map(|i| u16::from_le_bytes([b[2 * i], b[2 * i + 1]]))
    }
}

impl Element for [u8; 4] {
    fn write(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(self);
    }
    fn read(b: &[u8]) -> Self {
        [b[0], b[1], b[2], b[3]]
    }
}

/// `count` elements of `stride` bytes through the vertex codec.
fn encode_bytes(bytes: &[u8], stride: usize) -> Vec<u8> {
    macro_rules! with_words {
        ($($n:literal)*) => {
            match stride / 4 {
                $($n => {
                    let v: Vec<[u32; $n]> = bytes
                        .chunks_exact(4 * $n)
                        .map(|c| std::array::from_fn(|i| u32::from_le_bytes([c[4 * i], c[4 * i + 1], c[4 * i + 2], c[4 * i + 3]])))
                        .collect();
                    meshopt::encode_vertex_buffer_level(&v, VERTEX_LEVEL, Some(VERTEX_VERSION))
                })*
                _ => unreachable!("column stride {stride}"),
            }
        };
    }
    with_words!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
        .expect("meshopt encodes any buffer it bounded")
}

fn decode_bytes(encoded: &[u8], count: usize, stride: usize) -> Option<Vec<u8>> {
    macro_rules! with_words {
        ($($n:literal)*) => {
            match stride / 4 {
                $($n => meshopt::decode_vertex_buffer::<[u32; $n]>(encoded, count)
                    .ok()
                    .map(|v| v.iter().flatten().flat_map(|w| w.to_le_bytes()).collect()),)*
                _ => None,
            }
        };
    }
    with_words!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
}

/// Appends columns to a chunk.
#[derive(Default)]
pub(super) struct ColumnWriter {
    pub out: Vec<u8>,
}

impl ColumnWriter {
    fn put(&mut self, count: usize, bytes: &[u8]) {
        put_varint(&mut self.out, count as u64);
        put_varint(&mut self.out, bytes.len() as u64);
        self.out.extend_from_slice(bytes);
    }

    /// A vertex-codec column of `T`.
    pub fn vertices<T: Element>(&mut self, items: &[T]) {
        let mut raw = Vec::with_capacity(std::mem::size_of_val(items));
        for it in items {
            it.write(&mut raw);
        }
        self.strided(&raw, items.len(), std::mem::size_of::<T>());
    }

    /// A vertex-codec column of `count` elements of `stride` bytes.
    pub fn strided(&mut self, raw: &[u8], count: usize, stride: usize) {
        if count == 0 {
            self.put(0, &[]);
        } else {
            self.put(count, &encode_bytes(raw, stride));
        }
    }

    /// An index-sequence column (order and values kept exactly).
    pub fn sequence(&mut self, indices: &[u32], vertex_count: usize) {
        if indices.is_empty() {
            self.put(0, &[]);
        } else {
            let e = meshopt::encoding::encode_index_sequence(indices, vertex_count)
                .expect("meshopt encodes any sequence it bounded");
            self.put(indices.len(), &e);
        }
    }

    /// A raw bit column (`bits` bits, LSB first).
    pub fn bits(&mut self, bits: &BitWriter) {
        self.put(bits.len, &bits.bytes);
    }
}

/// Reads the columns of one whole chunk.
pub(super) struct ColumnReader<'a> {
    pub bytes: &'a [u8],
    pub pos: usize,
    /// Stream offset of `bytes[0]`.
    pub base: usize,
}

impl<'a> ColumnReader<'a> {
    pub fn offset(&self) -> usize {
        self.base + self.pos
    }

    pub fn varint(&mut self) -> Result<u64, StreamError> {
        let start = self.offset();
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let b = *self
                .bytes
                .get(self.pos)
                .ok_or_else(|| invalid(start, "column header runs past the chunk"))?;
            self.pos += 1;
            let bits = u64::from(b & 0x7f);
            if shift == 63 && bits > 1 {
                break;
            }
            v |= bits << shift;
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(invalid(start, "varint longer than 64 bits"))
    }

    /// The next column's element count (checked against `expect` when
    /// given, else against `limit`) and its bytes.
    fn next(
        &mut self,
        what: &str,
        expect: Option<usize>,
        limit: usize,
    ) -> Result<(usize, &'a [u8], usize), StreamError> {
        let at = self.offset();
        let count = self.varint()?;
        match expect {
            Some(n) if count != n as u64 => {
                return Err(invalid(
                    at,
                    format!("{what} column holds {count} values, expected {n}"),
                ))
            }
            None if count > limit as u64 => {
                return Err(invalid(
                    at,
                    format!("{what} column holds {count} values, over {limit}"),
                ))
            }
            _ => {}
        }
        let len = self.varint()?;
        let rest = (self.bytes.len() - self.pos) as u64;
        if len > rest {
            return Err(invalid(at, format!("{what} column runs past the chunk")));
        }
        // meshopt's codecs spend at least 2 bits per 256 values of a byte
        // lane: more values than this cannot be there (and would make the
        // decoder allocate for nothing)
        if count > 1024 * (len + 16) {
            return Err(invalid(
                at,
                format!("{what} column: {count} values in {len} bytes"),
            ));
        }
        let start = self.pos;
        self.pos += len as usize;
        Ok((count as usize, &self.bytes[start..self.pos], at))
    }

    /// A vertex-codec column of `T`.
    pub fn vertices<T: Element>(
        &mut self,
        what: &str,
        expect: Option<usize>,
        limit: usize,
    ) -> Result<Vec<T>, StreamError> {
        let size = std::mem::size_of::<T>();
        let raw = self.strided(what, expect, limit, size)?;
        Ok(raw.chunks_exact(size).map(T::read).collect())
    }

    /// A vertex-codec column of `stride`-byte elements, as bytes.
    pub fn strided(
        &mut self,
        what: &str,
        expect: Option<usize>,
        limit: usize,
        stride: usize,
    ) -> Result<Vec<u8>, StreamError> {
        let (count, bytes, at) = self.next(what, expect, limit)?;
        if count == 0 {
            return if bytes.is_empty() {
                Ok(Vec::new())
            } else {
                Err(invalid(at, format!("empty {what} column with bytes")))
            };
        }
        decode_bytes(bytes, count, stride)
            .ok_or_else(|| invalid(at, format!("{what} column: meshopt vertex decoding failed")))
    }

    /// An index-sequence column of exactly `count` indices.
    pub fn sequence(&mut self, what: &str, count: usize) -> Result<Vec<u32>, StreamError> {
        let (count, bytes, at) = self.next(what, Some(count), 0)?;
        if count == 0 {
            return Ok(Vec::new());
        }
        meshopt::encoding::decode_index_sequence::<u32>(bytes, count)
            .map_err(|_| invalid(at, format!("{what} column: meshopt index decoding failed")))
    }

    /// A raw bit column of at most `limit` bits.
    pub fn bits(&mut self, what: &str, limit: usize) -> Result<BitReader<'a>, StreamError> {
        let (count, bytes, at) = self.next(what, None, limit)?;
        if bytes.len() != count.div_ceil(8) {
            return Err(invalid(
                at,
                format!("{what} column: {count} bits in {} bytes", bytes.len()),
            ));
        }
        Ok(BitReader {
            bytes,
            len: count,
            pos: 0,
            at,
        })
    }

    /// Everything read: no bytes left over.
    pub fn finish(&self, what: &str) -> Result<(), StreamError> {
        if self.pos == self.bytes.len() {
            Ok(())
        } else {
            Err(invalid(
                self.offset(),
                format!("{} bytes left over in {what}", self.bytes.len() - self.pos),
            ))
        }
    }
}

/// Bits, LSB first.
#[derive(Default)]
pub(super) struct BitWriter {
    pub bytes: Vec<u8>,
    pub len: usize,
}

impl BitWriter {
    pub fn push(&mut self, bit: bool) {
        if self.len % 8 == 0 {
            self.bytes.push(0);
        }
        if bit {
            *self.bytes.last_mut().expect("pushed above") |= 1 << (self.len % 8);
        }
        self.len += 1;
    }
}

pub(super) struct BitReader<'a> {
    bytes: &'a [u8],
    len: usize,
    pos: usize,
    at: usize,
}

impl BitReader<'_> {
    pub fn next(&mut self) -> Result<bool, StreamError> {
        if self.pos >= self.len {
            return Err(invalid(self.at, "the corner-mask column ends early"));
        }
        let b = self.bytes[self.pos / 8] >> (self.pos % 8) & 1;
        self.pos += 1;
        Ok(b == 1)
    }

    pub fn finish(&self) -> Result<(), StreamError> {
        if self.pos == self.len {
            Ok(())
        } else {
            Err(invalid(
                self.at,
                format!("{} corner-mask bits left over", self.len - self.pos),
            ))
        }
    }
}

/// A cursor over a `u32` column read in order (the escape column).
pub(super) struct Words {
    pub words: Vec<u32>,
    pub pos: usize,
    pub at: usize,
}

impl Words {
    pub fn next(&mut self) -> Result<u32, StreamError> {
        let w = *self
            .words
            .get(self.pos)
            .ok_or_else(|| invalid(self.at, "the escape column ends early"))?;
        self.pos += 1;
        Ok(w)
    }

    pub fn finish(&self) -> Result<(), StreamError> {
        if self.pos == self.words.len() {
            Ok(())
        } else {
            Err(invalid(self.at, "escape words left over"))
        }
    }
}

/// Prefix sums of `u16` residuals per lane, so that meshopt's 16-bit delta
/// channel sees exactly the residuals.
pub(super) fn prefix_sums(residuals: &[[u16; 3]]) -> Vec<[u16; 4]> {
    let mut acc = [0u16; 3];
    residuals
        .iter()
        .map(|r| {
            for a in 0..3 {
                acc[a] = acc[a].wrapping_add(r[a]);
            }
            [acc[0], acc[1], acc[2], 0]
        })
        .collect()
}

/// The inverse of [`prefix_sums`].
pub(super) fn differences(sums: &[[u16; 4]]) -> Vec<[u16; 3]> {
    let mut prev = [0u16; 3];
    sums.iter()
        .map(|s| {
            let r = [0, 1, 2].map(|a| s[a].wrapping_sub(prev[a]));
            prev = [s[0], s[1], s[2]];
            r
        })
        .collect()
}
