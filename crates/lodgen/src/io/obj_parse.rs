//! OBJ statements, parsed in parallel: a batch of whole lines is cut into
//! chunks of about [`CHUNK_BYTES`] at line ends (the cut depends on the
//! bytes only, never on the number of threads). A first pass counts each
//! chunk's lines and `v` / `vt` / `vn` statements, so every chunk then
//! knows the line number and the vertex counts it starts at, and a second
//! pass parses all chunks at once: coordinates, faces fan-triangulated into
//! corners with every index resolved and checked against the counts so far,
//! and the statements that change where faces go ([`Event`]). A chunk stops
//! at its first error; the first chunk with one gives the file's error,
//! the same error at the same line a line-by-line read gives.
//!
//! Works on bytes: a token that is not UTF-8 cannot be a number, and a name
//! or a token quoted in an error is converted lossily, as the whole text
//! once was (ASCII whitespace never belongs to a malformed sequence).

use std::cell::Cell;
use std::ops::Range;
use std::path::Path;

use rayon::prelude::*;

use super::error::{ErrorKind, Location, ReadError};
use super::obj_plain::{is_space, lossy, plain_coords, plain_face, plain_texcoord, tokens};

pub(super) use super::obj_plain::NONE;

/// The size chunks are cut at (at the next line end).
pub(super) const CHUNK_BYTES: usize = 1 << 20;

/// Lines and vertex statements of a piece of text.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Counts {
    pub lines: usize,
    pub v: usize,
    pub vt: usize,
    pub vn: usize,
}

/// A statement that changes which primitive receives the next faces.
#[derive(Debug)]
pub(super) enum Event {
    /// `o name` (the name trimmed).
    Object(String),
    /// `usemtl name`.
    Material(String),
    /// `mtllib file...`.
    Library(Vec<String>),
}

/// What one chunk holds, every index absolute (0-based).
#[derive(Debug, Default)]
pub(super) struct Chunk {
    pub positions: Vec<[f32; 3]>,
    /// `v x y z r g b` colours, one per position once a `v` of the chunk has one (white
    /// before it; empty when none has).
    pub colors: Vec<[f32; 3]>,
    /// `[u, 1 - v]` (glTF's convention).
    pub texcoords: Vec<[f32; 2]>,
    pub normals: Vec<[f32; 3]>,
    /// The `v` of every triangle corner, faces fan-triangulated.
    pub v: Vec<u32>,
    /// The `vt` / `vn` of every corner ([`NONE`] when absent); empty when
    /// no corner of the chunk has one.
    pub vt: Vec<u32>,
    pub vn: Vec<u32>,
    /// Events, each with the number of corners in `v` before it.
    pub events: Vec<(usize, Event)>,
    /// The chunk's first error (everything above is what preceded it).
    pub error: Option<ReadError>,
}

/// Parses `bytes` (whole lines: the last one may lack its `\n` only at the
/// end of the file) starting at `base`, cut into chunks of about
/// `chunk_bytes`; returns the chunks in order and the counts after them.
pub(super) fn parse_batch(
    bytes: &[u8],
    base: Counts,
    chunk_bytes: usize,
    path: &Path,
    offset: Option<[f64; 3]>,
) -> (Vec<Chunk>, Counts) {
    let ranges = cut(bytes, chunk_bytes);
    // every chunk but the last needs its counts, for the ones after it
    let counts: Vec<Counts> = ranges[..ranges.len().saturating_sub(1)]
        .par_iter()
        .map(|r| count(&bytes[r.clone()]))
        .collect();
    let mut starts = Vec::with_capacity(ranges.len());
    let mut at = base;
    starts.push(at);
    for c in &counts {
        at = Counts {
            lines: at.lines + c.lines,
            v: at.v + c.v,
            vt: at.vt + c.vt,
            vn: at.vn + c.vn,
        };
        starts.push(at);
    }
    let chunks: Vec<Chunk> = ranges
        .par_iter()
        .zip(&starts)
        .map(|(r, &start)| parse_chunk(&bytes[r.clone()], start, path, offset))
        .collect();
    let last = chunks.last().map_or(base, |c| {
        let start = starts[starts.len() - 1];
        let lines = bytes[ranges[ranges.len() - 1].clone()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        Counts {
            lines: start.lines + lines,
            v: start.v + c.positions.len(),
            vt: start.vt + c.texcoords.len(),
            vn: start.vn + c.normals.len(),
        }
    });
    (chunks, last)
}

/// Cuts `bytes` into ranges of at least `size` bytes ending after a `\n`
/// (the last one at the end); one empty range for empty input.
fn cut(bytes: &[u8], size: usize) -> Vec<Range<usize>> {
    let mut out = Vec::with_capacity(bytes.len() / size.max(1) + 1);
    let mut start = 0;
    while start < bytes.len() || out.is_empty() {
        let probe = (start + size.max(1)).min(bytes.len());
        let end = match memchr::memchr(b'\n', &bytes[probe.saturating_sub(1)..]) {
            Some(i) if probe < bytes.len() => probe + i,
            _ => bytes.len(),
        };
        out.push(start..end);
        start = end;
    }
    out
}

/// The lines of `bytes` (split at `\n`, one trailing `\r` removed).
fn lines(bytes: &[u8]) -> impl Iterator<Item = &[u8]> {
    let mut rest = Some(bytes);
    std::iter::from_fn(move || {
        let r = rest?;
        let line = match memchr::memchr(b'\n', r) {
            Some(i) => {
                rest = Some(&r[i + 1..]);
                &r[..i]
            }
            None => {
                rest = None;
                r
            }
        };
        Some(line.strip_suffix(b"\r").unwrap_or(line))
    })
}

/// The statements lodgen reads, by keyword (the line's first token).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Keyword {
    V,
    Vt,
    Vn,
    F,
    O,
    Usemtl,
    Mtllib,
    Other,
}

/// The line's keyword and the rest of the line after it.
#[inline]
fn keyword(line: &[u8]) -> (Keyword, &[u8]) {
    // the common statements at the line's start first (what the general
    // scan below gives them too)
    match line {
        [b'v', c, ..] if is_space(*c) => return (Keyword::V, &line[1..]),
        [b'f', c, ..] if is_space(*c) => return (Keyword::F, &line[1..]),
        [b'v', b'n', c, ..] if is_space(*c) => return (Keyword::Vn, &line[2..]),
        [b'v', b't', c, ..] if is_space(*c) => return (Keyword::Vt, &line[2..]),
        _ => {}
    }
    let start = line
        .iter()
        .position(|&b| !is_space(b))
        .unwrap_or(line.len());
    let line = &line[start..];
    let end = line.iter().position(|&b| is_space(b)).unwrap_or(line.len());
    let k = match &line[..end] {
        b"v" => Keyword::V,
        b"vt" => Keyword::Vt,
        b"vn" => Keyword::Vn,
        b"f" => Keyword::F,
        b"o" => Keyword::O,
        b"usemtl" => Keyword::Usemtl,
        b"mtllib" => Keyword::Mtllib,
        _ => Keyword::Other,
    };
    (k, &line[end..])
}

fn count(bytes: &[u8]) -> Counts {
    let mut c = Counts::default();
    for line in lines(bytes) {
        match keyword(line).0 {
            Keyword::V => c.v += 1,
            Keyword::Vt => c.vt += 1,
            Keyword::Vn => c.vn += 1,
            _ => {}
        }
    }
    c.lines = memchr::memchr_iter(b'\n', bytes).count();
    c
}

/// Parsing one chunk: its output, where it is, and the face scratch.
struct ChunkParser<'a> {
    out: Chunk,
    path: &'a Path,
    line: usize,
    base: Counts,
    face: Vec<[u32; 3]>,
    /// The address of the token an error is about (0: none), set on the
    /// error path only: the error then names its column.
    bad: Cell<usize>,
    /// Subtracted from every `v` in `f64` (a file far from the origin: `Origin::Moved`).
    offset: Option<[f64; 3]>,
}

fn parse_chunk(bytes: &[u8], base: Counts, path: &Path, offset: Option<[f64; 3]>) -> Chunk {
    let mut p = ChunkParser {
        out: Chunk::default(),
        path,
        line: base.lines,
        base,
        face: Vec::new(),
        bad: Cell::new(0),
        offset,
    };
    for line in lines(bytes) {
        p.line += 1;
        if let Err(mut e) = p.statement(line) {
            // (the bad token's 1-based byte column, when known)
            let column = p.bad.get().wrapping_sub(line.as_ptr() as usize);
            if column < line.len() {
                e.location = Location::Column {
                    line: p.line,
                    column: column + 1,
                };
            }
            p.out.error = Some(e);
            break;
        }
    }
    p.out
}

impl ChunkParser<'_> {
    fn err(&self, kind: ErrorKind) -> ReadError {
        ReadError::new(self.path, Location::Line(self.line), kind)
    }

    fn statement(&mut self, line: &[u8]) -> Result<(), ReadError> {
        let (k, rest) = keyword(line);
        match k {
            Keyword::V => {
                let (p, end) = match (self.offset, plain_coords(rest)) {
                    (Some(o), _) => (self.moved_coords(rest, o)?, 0),
                    (None, Some(p)) => p,
                    (None, None) => (self.coords::<3>(rest, "vertex coordinate")?, 0),
                };
                self.out.positions.push(p);
                // (after three plain decimals, usually the line's end)
                let tail = &rest[end..];
                if tail.iter().any(|&b| !is_space(b)) {
                    self.vertex_colour(rest)?;
                }
            }
            Keyword::Vt => {
                let t = match plain_texcoord(rest) {
                    Some(t) => t,
                    None => self.texcoord(rest)?,
                };
                self.out.texcoords.push(t);
            }
            Keyword::Vn => {
                let n = match plain_coords(rest) {
                    Some((n, _)) => n,
                    None => self.coords::<3>(rest, "normal")?,
                };
                self.out.normals.push(n);
            }
            Keyword::F => self.face(rest)?,
            Keyword::O | Keyword::Usemtl => {
                let name = String::from_utf8_lossy(rest).trim().to_owned();
                let e = if k == Keyword::O {
                    Event::Object(name)
                } else {
                    Event::Material(name)
                };
                self.out.events.push((self.out.v.len(), e));
            }
            Keyword::Mtllib => {
                let files = tokens(rest)
                    .take_while(|t| !t.starts_with(b"#"))
                    .map(lossy)
                    .collect();
                self.out
                    .events
                    .push((self.out.v.len(), Event::Library(files)));
            }
            Keyword::Other => {}
        }
        Ok(())
    }

    /// An error about `token`, a piece of the line being read.
    fn err_at(&self, token: &[u8], kind: ErrorKind) -> ReadError {
        self.bad.set(token.as_ptr() as usize);
        self.err(kind)
    }

    /// `vt u [v]` as `[u, 1 - v]`.
    fn texcoord(&self, rest: &[u8]) -> Result<[f32; 2], ReadError> {
        let mut t = tokens(rest);
        let u = self.coords::<1>(rest, "texture coordinate")?[0];
        t.next();
        let v = match t.next() {
            Some(tok) if !tok.starts_with(b"#") => self.number(tok, "texture coordinate")?,
            _ => 0.0,
        };
        Ok([u, 1.0 - v])
    }

    /// One number token (as `str::parse::<f32>` reads it), finite.
    fn number(&self, token: &[u8], what: &str) -> Result<f32, ReadError> {
        let parsed = parse_f32(token);
        let Some(value) = parsed else {
            return Err(self.err_at(
                token,
                ErrorKind::Syntax {
                    expected: format!("a number for {what}"),
                    found: lossy(token),
                },
            ));
        };
        if !value.is_finite() {
            return Err(self.err_at(
                token,
                ErrorKind::NonFinite {
                    what: what.to_owned(),
                    value,
                },
            ));
        }
        Ok(value)
    }

    /// The first `N` numbers of `rest`; missing ones are a syntax error.
    fn coords<const N: usize>(&self, rest: &[u8], what: &str) -> Result<[f32; N], ReadError> {
        let mut t = tokens(rest);
        let mut out = [0.0f32; N];
        for slot in &mut out {
            let Some(token) = t.next() else {
                return Err(self.err(ErrorKind::Syntax {
                    expected: format!("{N} coordinates for {what}"),
                    found: "end of line".to_owned(),
                }));
            };
            *slot = self.number(token, what)?;
        }
        Ok(out)
    }

    /// `v x y z r g b` (MeshLab's and most scanners' vertex colours; components above 1 are
    /// taken as 0–255): the colour of the position just read. Three numbers after the
    /// coordinates make a colour; one (`w`) or none do not.
    fn vertex_colour(&mut self, rest: &[u8]) -> Result<(), ReadError> {
        let more: Vec<&[u8]> = tokens(rest)
            .skip(3)
            .take_while(|t| !t.starts_with(b"#"))
            .collect();
        if more.len() < 3 {
            return Ok(());
        }
        let mut c = [0.0f32; 3];
        for (slot, token) in c.iter_mut().zip(&more) {
            *slot = self.number(token, "vertex colour")?;
        }
        if c.iter().any(|&x| x > 1.0) {
            c = c.map(|x| x / 255.0);
        }
        self.out
            .colors
            .resize(self.out.positions.len() - 1, [1.0; 3]);
        self.out.colors.push(c);
        Ok(())
    }

    /// A `v` statement's coordinates less `offset`, subtracted in `f64` (then `f32`, finite).
    fn moved_coords(&self, rest: &[u8], offset: [f64; 3]) -> Result<[f32; 3], ReadError> {
        let mut t = tokens(rest);
        let mut out = [0.0f32; 3];
        for (slot, o) in out.iter_mut().zip(offset) {
            let Some(token) = t.next() else {
                return Err(self.err(ErrorKind::Syntax {
                    expected: "3 coordinates for vertex coordinate".to_owned(),
                    found: "end of line".to_owned(),
                }));
            };
            let Some(value) = fast_float2::parse::<f64, _>(token).ok() else {
                return Err(self.err_at(
                    token,
                    ErrorKind::Syntax {
                        expected: "a number for vertex coordinate".to_owned(),
                        found: lossy(token),
                    },
                ));
            };
            *slot = (value - o) as f32;
            if !slot.is_finite() {
                let kind = ErrorKind::NonFinite {
                    what: "vertex coordinate".to_owned(),
                    value: *slot,
                };
                return Err(self.err_at(token, kind));
            }
        }
        Ok(out)
    }

    /// One OBJ index (1-based or negative) against `count` items.
    fn resolve(&self, token: &[u8], count: usize, target: &'static str) -> Result<u32, ReadError> {
        let Some(index) = parse_i64(token) else {
            return Err(self.err_at(
                token,
                ErrorKind::Syntax {
                    expected: format!("a {target} index"),
                    found: lossy(token),
                },
            ));
        };
        let resolved = match index {
            0 => return Err(self.err_at(token, ErrorKind::ObjIndexZero { target })),
            i if i > 0 => i - 1,
            i => count as i64 + i,
        };
        if resolved < 0 || resolved >= count as i64 {
            return Err(self.err_at(
                token,
                ErrorKind::IndexOutOfRange {
                    what: "face",
                    target,
                    index,
                    count,
                },
            ));
        }
        Ok(resolved as u32)
    }

    fn face(&mut self, rest: &[u8]) -> Result<(), ReadError> {
        let mut face = std::mem::take(&mut self.face);
        face.clear();
        let counts = (
            self.base.v + self.out.positions.len(),
            self.base.vt + self.out.texcoords.len(),
            self.base.vn + self.out.normals.len(),
        );
        if plain_face(rest, counts, &mut face).is_none() {
            // the general reading, for the same corners or the line's error
            face.clear();
            self.face_corners(rest, counts, &mut face)?;
        }
        self.emit_face(&face);
        self.face = face;
        Ok(())
    }

    /// The corners of a face line, each token split at `/`.
    fn face_corners(
        &self,
        rest: &[u8],
        counts: (usize, usize, usize),
        face: &mut Vec<[u32; 3]>,
    ) -> Result<(), ReadError> {
        for corner in tokens(rest).take_while(|t| !t.starts_with(b"#")) {
            let mut parts = corner.split(|&b| b == b'/');
            let v = parts.next().unwrap_or(b"");
            let vt = parts.next().filter(|s| !s.is_empty());
            let vn = parts.next().filter(|s| !s.is_empty());
            let v = self.resolve(v, counts.0, "vertex")?;
            let vt = match vt {
                Some(t) => self.resolve(t, counts.1, "texture coordinate")?,
                None => NONE,
            };
            let vn = match vn {
                Some(t) => self.resolve(t, counts.2, "normal")?,
                None => NONE,
            };
            face.push([v, vt, vn]);
        }
        if face.len() < 3 {
            return Err(self.err(ErrorKind::Invalid(format!(
                "face has {} corners, needs at least 3",
                face.len()
            ))));
        }
        Ok(())
    }

    /// A face's corners, fan-triangulated, into the chunk.
    fn emit_face(&mut self, face: &[[u32; 3]]) {
        let out = &mut self.out;
        // (`vt` / `vn` become lists at the chunk's first corner with one)
        let with_vt = !out.vt.is_empty() || face.iter().any(|c| c[1] != NONE);
        let with_vn = !out.vn.is_empty() || face.iter().any(|c| c[2] != NONE);
        if with_vt {
            out.vt.resize(out.v.len(), NONE);
        }
        if with_vn {
            out.vn.resize(out.v.len(), NONE);
        }
        for i in 1..face.len() - 1 {
            for c in [face[0], face[i], face[i + 1]] {
                out.v.push(c[0]);
                if with_vt {
                    out.vt.push(c[1]);
                }
                if with_vn {
                    out.vn.push(c[2]);
                }
            }
        }
    }
}

/// The coordinates of the first `v` statement of `bytes`, in `f64` (`None`: none, or not
/// three numbers): where the file is, for [`crate::io::far_offset`].
pub(super) fn first_vertex(bytes: &[u8]) -> Option<[f64; 3]> {
    let rest = lines(bytes).find_map(|line| match keyword(line) {
        (Keyword::V, rest) => Some(rest),
        _ => None,
    })?;
    let mut t = tokens(rest);
    let mut out = [0.0; 3];
    for slot in &mut out {
        *slot = fast_float2::parse::<f64, _>(t.next()?).ok()?;
    }
    Some(out)
}

/// `str::parse::<f32>` on bytes (both round correctly; what they accept
/// is the same, `parse_f32_reads_what_str_parse_reads`).
fn parse_f32(s: &[u8]) -> Option<f32> {
    fast_float2::parse(s).ok()
}

/// `str::parse::<i64>`: an optional sign, then at least one digit.
pub(super) fn parse_i64(s: &[u8]) -> Option<i64> {
    let (negative, digits) = match s.first() {
        Some(b'-') => (true, &s[1..]),
        Some(b'+') => (false, &s[1..]),
        _ => (false, s),
    };
    if digits.is_empty() {
        return None;
    }
    // accumulated negatively, so that i64::MIN fits
    let mut x: i64 = 0;
    for &c in digits {
        let d = c.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        x = x.checked_mul(10)?.checked_sub(i64::from(d))?;
    }
    if negative {
        Some(x)
    } else {
        x.checked_neg()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_i64_reads_what_str_parse_reads() {
        for s in [
            "1",
            "+1",
            "-1",
            "0",
            "-0",
            "007",
            "",
            "+",
            "-",
            "+-1",
            "1a",
            " 1",
            "9223372036854775807",
            "9223372036854775808",
            "-9223372036854775808",
            "-9223372036854775809",
            "1.0",
            "١",
        ] {
            assert_eq!(parse_i64(s.as_bytes()), s.parse::<i64>().ok(), "{s:?}");
        }
    }

    #[test]
    fn parse_f32_reads_what_str_parse_reads() {
        let mut cases: Vec<String> = [
            "0",
            "-0",
            "+0",
            "1",
            "1.",
            ".5",
            "-.5",
            "+.5",
            ".",
            "-",
            "+",
            "",
            "e5",
            "1e5",
            "1E5",
            "1e+5",
            "1e-5",
            "1e",
            "1e+",
            "1.5e3x",
            "0x10",
            "inf",
            "-inf",
            "+inf",
            "Inf",
            "INFINITY",
            "infinity",
            "-Infinity",
            "infin",
            "nan",
            "NaN",
            "-nan",
            "+nan",
            "nan(1)",
            "1_0",
            "1,5",
            "١",
            "1e400",
            "-1e400",
            "1e-50",
            "3.4028235e38",
            "3.4028236e38",
            "1.17549435e-38",
            "1.4e-45",
            "7e-46",
            "00.001",
            "1..2",
            "1.2.3",
            " 1",
            "1 ",
            "0.000000000000000000000000000000000000000000001",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        cases.push("1".repeat(400));
        cases.push(format!("0.{}1", "0".repeat(800)));
        for s in &cases {
            let ours = parse_f32(s.as_bytes()).map(f32::to_bits);
            assert_eq!(ours, s.parse::<f32>().ok().map(f32::to_bits), "{s:?}");
        }
        // every string of five characters from a numeric alphabet
        let alphabet = b"0159.e-+";
        for n in 0..alphabet.len().pow(5) {
            let mut k = n;
            let s: Vec<u8> = (0..5)
                .map(|_| {
                    let c = alphabet[k % alphabet.len()];
                    k /= alphabet.len();
                    c
                })
                .collect();
            let text = std::str::from_utf8(&s).unwrap();
            let ours = parse_f32(&s).map(f32::to_bits);
            assert_eq!(ours, text.parse::<f32>().ok().map(f32::to_bits), "{text:?}");
        }
    }

    /// The face, vertex and texture lines read by the fast paths and by the
    /// general reading give the same values, or the fast path declines.
    #[test]
    fn plain_lines_read_as_the_general_reading() {
        let path = Path::new("t.obj");
        let base = Counts {
            lines: 0,
            v: 9,
            vt: 5,
            vn: 4,
        };
        let p = ChunkParser {
            out: Chunk::default(),
            path,
            line: 1,
            base,
            face: Vec::new(),
            bad: Cell::new(0),
            offset: None,
        };
        let counts = (9, 5, 4);
        let faces = [
            " 1 2 3",
            " 1 2 3 4 # x",
            " 1/1 2/2 3/3",
            " 1//1 2//2 3//4",
            " 1/2/3 4/5/4 -1/-1/-1",
            " 1/ 2/ 3/",
            " 1/2/ 2// 3/1/",
            "\t1 2\t3 ",
            " 1 2",
            " 1 2 #3",
            " 1 2 3#",
            " 1 2 10",
            " 0 1 2",
            " 1 2 -10",
            " 1/6 2 3",
            " 1//5 2 3",
            " 1/x 2 3",
            " 1/2/3/4 2 3",
            " +1 2 3",
            " 1 2 3 -",
            " 1-2 2 3",
            " 99999999999999999999 1 2",
            " 1 2 3 \u{b}4",
        ];
        let mut plain_taken = 0;
        for line in faces {
            let (mut a, mut b) = (Vec::new(), Vec::new());
            let general = p.face_corners(line.as_bytes(), counts, &mut b);
            if plain_face(line.as_bytes(), counts, &mut a).is_some() {
                plain_taken += 1;
                assert!(general.is_ok(), "{line:?}");
                assert_eq!(a, b, "{line:?}");
            }
        }
        assert!(plain_taken >= 8, "{plain_taken}");
        let coords = [
            " 1 2 3",
            " -0.5 +.25 7.",
            "\t1\t2\t3 4 5",
            " 1 2",
            " 1 2 3e1",
            " 1 2 #",
            " 1e400 0 0",
            " 0.000001 1 2 # c",
            " 1 2 3x",
        ];
        for line in coords {
            if let Some((c, _)) = plain_coords(line.as_bytes()) {
                let g = p
                    .coords::<3>(line.as_bytes(), "x")
                    .map(|c| c.map(f32::to_bits));
                assert_eq!(
                    Ok(c.map(f32::to_bits)),
                    g.map_err(|e| e.to_string()),
                    "{line:?}"
                );
            }
            let t = plain_texcoord(line.as_bytes()).map(|t| t.map(f32::to_bits));
            if let Some(t) = t {
                let g = p.texcoord(line.as_bytes()).map(|t| t.map(f32::to_bits));
                assert_eq!(Ok(t), g.map_err(|e| e.to_string()), "{line:?}");
            }
        }
        assert!(plain_coords(b" 1 2").is_none() && plain_texcoord(b" 1 #").is_some());
    }

    #[test]
    fn cut_ends_every_range_after_a_line_end() {
        let text = b"v 1 2 3\nv 4 5 6\n\nf 1 2 3\nf 1 2 3";
        for size in 1..text.len() + 2 {
            let ranges = cut(text, size);
            assert_eq!(ranges[0].start, 0);
            assert_eq!(ranges.last().unwrap().end, text.len());
            for w in ranges.windows(2) {
                assert_eq!(w[0].end, w[1].start);
                assert_eq!(text[w[0].end - 1], b'\n', "size {size}: {ranges:?}");
                assert!(w[0].len() >= size.min(text.len()));
            }
        }
        assert_eq!(cut(b"", 4), vec![0..0]);
    }
}
