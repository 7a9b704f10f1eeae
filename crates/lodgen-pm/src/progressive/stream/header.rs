//! The stream header: writing it, and parsing it from a prefix that may
//! still be incomplete.

use super::columns::put_varint;
use super::types::{
    invalid, AttrEncoding, Channel, ChunkInfo, Grid, Range, StreamError, StreamHeader, WedgeLayout,
    FLAG_ERRORS, FLAG_WEDGES, MAGIC, MAX_CHANNELS, MAX_CHANNEL_NAME, MAX_COMPONENTS, VERSION,
};

/// The header's bytes (with `h.chunks` as given).
pub(super) fn write(h: &StreamHeader) -> Vec<u8> {
    let mut out = Vec::with_capacity(128);
    out.extend_from_slice(&MAGIC);
    out.push(VERSION);
    out.push(h.flags);
    out.push(h.grid.bits);
    for c in h.grid.center.iter().chain([&h.grid.half]) {
        out.extend_from_slice(&c.to_le_bytes());
    }
    for n in [
        h.base_vertices,
        h.base_triangles,
        h.split_count,
        h.total_vertices,
        h.total_triangles,
        h.levels.len(),
    ] {
        put_varint(&mut out, n as u64);
    }
    for &k in &h.levels {
        put_varint(&mut out, k as u64);
    }
    if let Some(layout) = &h.wedges {
        put_varint(&mut out, layout.total as u64);
        put_varint(&mut out, u64::from(layout.groups));
        put_varint(&mut out, layout.channels.len() as u64);
        for c in &layout.channels {
            put_varint(&mut out, c.name.len() as u64);
            out.extend_from_slice(c.name.as_bytes());
            out.push(c.components);
        }
        for e in &layout.encodings {
            out.push(e.code());
            if let AttrEncoding::Unorm16Range(r) = e {
                out.extend_from_slice(&r.offset.to_le_bytes());
                out.extend_from_slice(&r.scale.to_le_bytes());
            }
        }
    }
    put_varint(&mut out, h.chunks.len() as u64);
    for c in &h.chunks {
        put_varint(&mut out, c.records as u64);
        put_varint(&mut out, c.bytes as u64);
    }
    out
}

/// Reading from a prefix of the stream: running out of bytes is
/// [`ReadError::NeedMore`].
pub(super) struct Reader<'a> {
    pub bytes: &'a [u8],
    pub pos: usize,
}

pub(super) enum ReadError {
    NeedMore,
    Bad(StreamError),
}

impl From<StreamError> for ReadError {
    fn from(e: StreamError) -> Self {
        ReadError::Bad(e)
    }
}

impl Reader<'_> {
    fn byte(&mut self) -> Result<u8, ReadError> {
        let b = *self.bytes.get(self.pos).ok_or(ReadError::NeedMore)?;
        self.pos += 1;
        Ok(b)
    }

    fn f64(&mut self) -> Result<f64, ReadError> {
        let mut b = [0u8; 8];
        for x in &mut b {
            *x = self.byte()?;
        }
        Ok(f64::from_le_bytes(b))
    }

    fn f32(&mut self) -> Result<f32, ReadError> {
        let mut b = [0u8; 4];
        for x in &mut b {
            *x = self.byte()?;
        }
        Ok(f32::from_le_bytes(b))
    }

    fn varint(&mut self) -> Result<u64, ReadError> {
        let start = self.pos;
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let b = self.byte()?;
            let bits = u64::from(b & 0x7f);
            if shift == 63 && bits > 1 {
                break;
            }
            v |= bits << shift;
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(invalid(start, "varint longer than 64 bits").into())
    }

    /// A varint that must fit `limit` (inclusive).
    fn bounded(&mut self, limit: u64, what: &str) -> Result<u64, ReadError> {
        let start = self.pos;
        let v = self.varint()?;
        if v > limit {
            return Err(invalid(start, format!("{what} {v} exceeds {limit}")).into());
        }
        Ok(v)
    }
}

fn parse_grid(r: &mut Reader) -> Result<(u8, Grid), ReadError> {
    let at = r.pos;
    let flags = r.byte()?;
    if flags & !(FLAG_ERRORS | FLAG_WEDGES) != 0 {
        return Err(invalid(at, format!("unknown flags {flags:#04x}")).into());
    }
    let at = r.pos;
    let bits = r.byte()?;
    if !(2..=16).contains(&bits) {
        return Err(invalid(at, format!("grid bits {bits} outside 2..=16")).into());
    }
    let at = r.pos;
    let center = [r.f64()?, r.f64()?, r.f64()?];
    let half = r.f64()?;
    if !(center.iter().all(|c| c.is_finite()) && half.is_finite() && half > 0.0) {
        return Err(invalid(at, "non-finite grid center or non-positive half extent").into());
    }
    Ok((flags, Grid { center, half, bits }))
}

fn parse_wedges(r: &mut Reader, max: u64) -> Result<WedgeLayout, ReadError> {
    let total = r.bounded(max, "wedge count")? as usize;
    let at = r.pos;
    let groups = r.bounded(max, "group count")? as u32;
    if groups == 0 {
        return Err(invalid(at, "zero wedge groups").into());
    }
    let n = r.bounded(MAX_CHANNELS as u64, "channel count")? as usize;
    let mut channels = Vec::with_capacity(n);
    for _ in 0..n {
        let at = r.pos;
        let len = r.bounded(MAX_CHANNEL_NAME as u64, "channel name length")? as usize;
        let mut name = Vec::with_capacity(len);
        for _ in 0..len {
            name.push(r.byte()?);
        }
        let name = String::from_utf8(name)
            .ok()
            .filter(|n| !n.is_empty())
            .ok_or_else(|| invalid(at, "channel name empty or not UTF-8"))?;
        let at = r.pos;
        let components = r.byte()?;
        if !(1..=MAX_COMPONENTS).contains(&components) {
            return Err(invalid(
                at,
                format!("{components} components (1..={MAX_COMPONENTS})"),
            )
            .into());
        }
        channels.push(Channel { name, components });
    }
    let mut encodings = Vec::with_capacity(n);
    for _ in 0..n {
        let at = r.pos;
        let code = r.byte()?;
        let mut range = Range {
            offset: 0.0,
            scale: 1.0,
        };
        if code == 4 {
            let at = r.pos;
            let [offset, scale] = [r.f32()?, r.f32()?];
            range = Range { offset, scale };
            if !range.valid() {
                return Err(invalid(
                    at,
                    format!("attribute range offset {offset} scale {scale} (finite, scale > 0)"),
                )
                .into());
            }
        }
        encodings.push(
            AttrEncoding::from_code(code, range)
                .ok_or_else(|| invalid(at, format!("unknown attribute encoding {code}")))?,
        );
    }
    Ok(WedgeLayout {
        total,
        groups,
        channels,
        encodings,
    })
}

fn parse_chunks(r: &mut Reader, split_count: usize) -> Result<Vec<ChunkInfo>, ReadError> {
    let at = r.pos;
    let n = r.bounded(1 << 16, "chunk count")? as usize;
    if n == 0 {
        return Err(invalid(at, "no chunks").into());
    }
    let mut chunks = Vec::with_capacity(n);
    let mut prev = 0usize;
    for i in 0..n {
        let at = r.pos;
        let records = r.bounded(split_count as u64, "chunk record count")? as usize;
        let ok = if i == 0 { records == 0 } else { records > prev };
        if !ok {
            return Err(invalid(at, format!("chunk {i} ends at record {records}")).into());
        }
        let bytes = r.bounded(u64::from(u32::MAX), "chunk length")? as usize;
        chunks.push(ChunkInfo { records, bytes });
        prev = records;
    }
    if prev != split_count {
        return Err(invalid(
            at,
            format!("the chunks end at record {prev}, not {split_count}"),
        )
        .into());
    }
    Ok(chunks)
}

pub(super) fn parse(r: &mut Reader) -> Result<StreamHeader, ReadError> {
    for &m in &MAGIC {
        if r.byte()? != m {
            return Err(StreamError::Magic.into());
        }
    }
    let version = r.byte()?;
    if version != VERSION {
        return Err(StreamError::Version(version).into());
    }
    let (flags, grid) = parse_grid(r)?;
    let max = u64::from(u32::MAX - 1);
    let base_vertices = r.bounded(max, "base vertex count")? as usize;
    let base_triangles = r.bounded(max, "base triangle count")? as usize;
    let split_count = r.bounded(max, "split count")? as usize;
    let at = r.pos;
    let total_vertices = r.bounded(max, "total vertex count")? as usize;
    if total_vertices != base_vertices + split_count {
        return Err(invalid(
            at,
            format!(
                "total vertices {total_vertices} ≠ base {base_vertices} + splits {split_count}"
            ),
        )
        .into());
    }
    let at = r.pos;
    // below 2^30 like every mesh (`Mesh::validate`): split corners are
    // packed into 30 bits (`Corners`)
    let total_triangles = r.bounded((1 << 30) - 1, "total triangle count")? as usize;
    if total_triangles < base_triangles {
        return Err(invalid(at, "total triangles below the base count").into());
    }
    let level_count = r.bounded(1 << 16, "level count")? as usize;
    let mut levels = Vec::with_capacity(level_count.min(64));
    for _ in 0..level_count {
        levels.push(r.bounded(split_count as u64, "level record count")? as usize);
    }
    let wedges = if flags & FLAG_WEDGES != 0 {
        Some(parse_wedges(r, max)?)
    } else {
        None
    };
    let chunks = parse_chunks(r, split_count)?;
    Ok(StreamHeader {
        flags,
        grid,
        base_vertices,
        base_triangles,
        split_count,
        total_vertices,
        total_triangles,
        levels,
        wedges,
        chunks,
        header_bytes: r.pos,
    })
}
