//! Bytes per column kind of a stream, summed over its chunks: what
//! `cargo xtask stream-bench --bytes` prints to show where a stream's
//! bytes go.

use super::columns::ColumnReader;
use super::decode::decode_header;
use super::types::{invalid, StreamError, StreamHeader, BLOCK_RECORDS, FLAG_ERRORS};

/// One column kind's total over the stream's chunks.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ColumnStat {
    /// The kind, as docs/LODGEN_progressive.md names it (`base position`,
    /// `v1`, `new`, a channel's name, …).
    pub name: String,
    /// Values (elements, indices or bits) over all chunks.
    pub count: usize,
    /// Bytes, column headers included.
    pub bytes: usize,
}

/// The names of a chunk's columns in order (`base`: chunk 0; else a chunk
/// of `records` records: its blocks' columns, then its positions).
fn names(h: &StreamHeader, base: bool, records: usize) -> Vec<String> {
    let mut wedges = Vec::new();
    if let Some(w) = &h.wedges {
        let p = if base { "base " } else { "" };
        wedges.push(format!("{p}wedge refs"));
        if w.groups > 1 {
            wedges.push(format!("{p}wedge groups"));
        }
        wedges.extend(w.channels.iter().map(|c| format!("{p}{}", c.name)));
    }
    if base {
        let mut out: Vec<String> = vec!["base position".into(), "base triangles".into()];
        out.extend(wedges);
        return out;
    }
    let mut out = Vec::new();
    // the blocks' topology and wedge columns, then the positions (version 7)
    for _ in 0..records.div_ceil(BLOCK_RECORDS) {
        out.extend(["v1", "head", "escape", "mask"].map(String::from));
        out.extend(wedges.iter().cloned());
    }
    out.extend(["moved", "new"].map(String::from));
    if h.flags & FLAG_ERRORS != 0 {
        out.push("errors".into());
    }
    out
}

/// Bytes per column kind (first the header, then in order of first
/// appearance), or an error when the stream's column structure is broken.
/// Values are not decoded.
pub fn column_stats(bytes: &[u8]) -> Result<Vec<ColumnStat>, StreamError> {
    let h = decode_header(bytes)?;
    let mut out = vec![ColumnStat {
        name: "header".into(),
        count: 1,
        bytes: h.header_bytes,
    }];
    for (i, c) in h.chunks.iter().enumerate() {
        let at = h.chunk_offset(i);
        let chunk = bytes
            .get(at..at + c.bytes)
            .ok_or_else(|| invalid(at, "chunk cut short"))?;
        let mut r = ColumnReader {
            bytes: chunk,
            pos: 0,
            base: at,
        };
        let records = c.records - if i == 0 { 0 } else { h.chunks[i - 1].records };
        for name in names(&h, i == 0, records) {
            let start = r.pos;
            let count = r.varint()? as usize;
            let len = r.varint()? as usize;
            if len > chunk.len() - r.pos {
                return Err(invalid(
                    r.offset(),
                    format!("{name} column runs past the chunk"),
                ));
            }
            r.pos += len;
            let bytes = r.pos - start;
            match out.iter_mut().find(|s| s.name == name) {
                Some(s) => {
                    s.count += count;
                    s.bytes += bytes;
                }
                None => out.push(ColumnStat { name, count, bytes }),
            }
        }
        r.finish("a chunk")?;
    }
    Ok(out)
}
