//! The OBJ statements' fast paths: the usual forms of `v`, `vt`, `vn` and
//! `f` read without tokens or error reporting (bunny.obj: ≈ 53 → ≈ 33
//! instructions a byte for the whole parse). Each gives exactly what the
//! general reading in [`super::obj_parse`] gives, or `None`, and then the
//! line is read again the general way (for its value or its error).

/// "No texture coordinate / normal" in a corner.
pub(super) const NONE: u32 = u32::MAX;

/// OBJ's token separators.
#[inline]
pub(super) fn is_space(b: u8) -> bool {
    b.is_ascii_whitespace()
}

/// Skips ASCII whitespace from `i`.
#[inline]
fn skip_space(s: &[u8], mut i: usize) -> usize {
    while i < s.len() && is_space(s[i]) {
        i += 1;
    }
    i
}

/// `10^k`, every one exact in `f32`.
const POW10: [f32; 10] = [1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9];
const POW10_INT: [u64; 10] = [
    1,
    10,
    100,
    1_000,
    10_000,
    100_000,
    1_000_000,
    10_000_000,
    100_000_000,
    1_000_000_000,
];

/// An optional sign: whether it is `-`, and where the digits start.
#[inline(always)]
fn sign(s: &[u8]) -> (bool, usize) {
    match s.first() {
        Some(b'-') => (true, 1),
        Some(b'+') => (false, 1),
        _ => (false, 0),
    }
}

/// The digits of `s` from `i` on, as a number (wrapping past 19 digits)
/// and where they end.
#[inline(always)]
fn digits(s: &[u8], mut i: usize) -> (u64, usize) {
    let mut x: u64 = 0;
    while let Some(&c) = s.get(i) {
        let d = c.wrapping_sub(b'0');
        if d > 9 {
            break;
        }
        x = x.wrapping_mul(10).wrapping_add(u64::from(d));
        i += 1;
    }
    (x, i)
}

/// A plain decimal at the start of `s` — `[+-]digits[.digits]`, at least
/// one digit, at most 9, ended by whitespace or the end of `s` — when one
/// division gives its value: its digits as an integer `m ≤ 2^24` over
/// `10^k` (both exact in `f32`, so the quotient is the correctly rounded
/// value [`parse_f32`] gives, Clinger's fast path). The value and the bytes
/// it took.
#[inline]
fn plain_decimal(s: &[u8]) -> Option<(f32, usize)> {
    let (negative, start) = sign(s);
    let (int, int_end) = digits(s, start);
    let (frac, frac_start, end) = if s.get(int_end) == Some(&b'.') {
        let (frac, end) = digits(s, int_end + 1);
        (frac, int_end + 1, end)
    } else {
        (0, int_end, int_end)
    };
    let scale = end - frac_start;
    let count = (int_end - start) + scale;
    if count == 0 || count > 9 {
        return None;
    }
    // (at most 9 digits: nothing wrapped)
    let m = int * POW10_INT[scale] + frac;
    if m > 1 << 24 {
        return None;
    }
    if let Some(&c) = s.get(end) {
        if !is_space(c) {
            return None;
        }
    }
    let value = m as f32 / POW10[scale];
    Some((if negative { -value } else { value }, end))
}

/// `v` / `vn` with three plain decimals (what follows them is ignored, as
/// in [`ChunkParser::coords`]), and where they end in `rest`.
#[inline]
pub(super) fn plain_coords(rest: &[u8]) -> Option<([f32; 3], usize)> {
    let mut out = [0.0f32; 3];
    let mut i = 0;
    for slot in &mut out {
        i = skip_space(rest, i);
        let (x, n) = plain_decimal(&rest[i..])?;
        *slot = x;
        i += n;
    }
    Some((out, i))
}

/// `vt u [v]` with plain decimals, as `[u, 1 - v]`.
#[inline]
pub(super) fn plain_texcoord(rest: &[u8]) -> Option<[f32; 2]> {
    let i = skip_space(rest, 0);
    let (u, n) = plain_decimal(&rest[i..])?;
    let i = skip_space(rest, i + n);
    let v = match rest.get(i) {
        None | Some(b'#') => 0.0,
        Some(_) => plain_decimal(&rest[i..])?.0,
    };
    Some([u, 1.0 - v])
}

/// An index at the start of `s`: an optional sign and 1 to 18 digits
/// (whatever follows is the caller's); its value and the bytes it took.
#[inline(always)]
fn plain_index(s: &[u8]) -> Option<(i64, usize)> {
    let (negative, start) = sign(s);
    let (x, end) = digits(s, start);
    if end == start || end - start > 18 {
        return None;
    }
    let x = x as i64;
    Some((if negative { -x } else { x }, end))
}

/// [`ChunkParser::resolve`] of an index that resolves.
#[inline]
fn plain_resolve(index: i64, count: usize) -> Option<u32> {
    let resolved = match index {
        0 => return None,
        i if i > 0 => i - 1,
        i => count as i64 + i,
    };
    (resolved >= 0 && resolved < count as i64).then_some(resolved as u32)
}

/// A face of at least 3 corners `v`, `v/vt`, `v//vn` or `v/vt/vn` (plain
/// indices, all in range; a token starting with `#` ends it) into `face`.
pub(super) fn plain_face(
    rest: &[u8],
    counts: (usize, usize, usize),
    face: &mut Vec<[u32; 3]>,
) -> Option<()> {
    let mut i = 0;
    loop {
        i = skip_space(rest, i);
        match rest.get(i) {
            None | Some(b'#') => break,
            Some(_) => {}
        }
        let (v, n) = plain_index(&rest[i..])?;
        i += n;
        let mut corner = [plain_resolve(v, counts.0)?, NONE, NONE];
        if rest.get(i) == Some(&b'/') {
            i += 1;
            if let Some((t, n)) = plain_index(&rest[i..]) {
                i += n;
                corner[1] = plain_resolve(t, counts.1)?;
            }
            if rest.get(i) == Some(&b'/') {
                i += 1;
                if let Some((t, n)) = plain_index(&rest[i..]) {
                    i += n;
                    corner[2] = plain_resolve(t, counts.2)?;
                }
            }
        }
        match rest.get(i) {
            Some(&c) if !is_space(c) => return None,
            _ => {}
        }
        face.push(corner);
    }
    (face.len() >= 3).then_some(())
}

/// The ASCII-whitespace separated tokens of `s`.
pub(super) fn tokens(s: &[u8]) -> Tokens<'_> {
    Tokens { rest: s }
}

pub(super) struct Tokens<'a> {
    rest: &'a [u8],
}

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a [u8];

    #[inline]
    fn next(&mut self) -> Option<&'a [u8]> {
        let mut s = self.rest;
        while let [first, tail @ ..] = s {
            if !is_space(*first) {
                break;
            }
            s = tail;
        }
        if s.is_empty() {
            self.rest = s;
            return None;
        }
        let end = s.iter().position(|&b| is_space(b)).unwrap_or(s.len());
        self.rest = &s[end..];
        Some(&s[..end])
    }
}

/// A token as text, for an error message.
pub(super) fn lossy(t: &[u8]) -> String {
    String::from_utf8_lossy(t).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::obj_parse::parse_i64;

    /// `plain_decimal` of `s`, if any, is the whole token and its value is
    /// `str::parse`'s, also followed by more text.
    fn check_plain_decimal(s: &str) -> bool {
        let expected = s.parse::<f32>().ok().map(f32::to_bits);
        let plain = plain_decimal(s.as_bytes());
        if let Some((x, n)) = plain {
            assert_eq!(n, s.len(), "{s:?}");
            assert_eq!(Some(x.to_bits()), expected, "{s:?}");
        }
        let followed = format!("{s} 7");
        let again = plain_decimal(followed.as_bytes());
        assert_eq!(
            again.map(|(x, n)| (x.to_bits(), n)),
            plain.map(|(x, n)| (x.to_bits(), n))
        );
        plain.is_some()
    }

    #[test]
    fn plain_decimals_are_what_str_parse_reads() {
        for s in [
            "0", "-0", "+0", "1.", ".5", "-.5", "+.5", "00.001", "16777216",
        ] {
            assert!(check_plain_decimal(s), "{s:?}");
        }
        for s in [
            ".",
            "-",
            "",
            "1e5",
            "1.2.3",
            "1,5",
            "0.0000000001",
            "1234567890",
            "inf",
            "1x",
        ] {
            assert!(!check_plain_decimal(s), "{s:?}");
        }
        // every string of five characters from a numeric alphabet
        let alphabet = b"0159.-+";
        for n in 0..alphabet.len().pow(5) {
            let mut k = n;
            let s: String = (0..5)
                .map(|_| {
                    let c = alphabet[k % alphabet.len()];
                    k /= alphabet.len();
                    c as char
                })
                .collect();
            check_plain_decimal(&s);
        }
        // random decimals of up to 9 digits, both sides of the point
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut taken = 0;
        for _ in 0..200_000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            let r = state >> 11;
            let int = (r % 10_000_000) as u32 % 10u32.pow((r >> 24) as u32 % 8);
            let frac_len = (r >> 27) as usize % 10;
            let frac = (r >> 31) % 1_000_000_000;
            let sign = ["", "-", "+"][(r >> 61) as usize % 3];
            let s = format!("{sign}{int}.{frac:09}");
            taken += usize::from(check_plain_decimal(&s[..s.len() - 9 + frac_len]));
        }
        assert!(taken > 50_000, "{taken}");
    }

    #[test]
    fn plain_indices_are_what_str_parse_reads() {
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
            "123456789012345678",
            "1234567890123456789",
            "-999999999999999999",
        ] {
            let plain = plain_index(s.as_bytes());
            if let Some((x, n)) = plain {
                assert_eq!(n, s.len(), "{s:?}");
                assert_eq!(Some(x), parse_i64(s.as_bytes()), "{s:?}");
            } else {
                assert!(s.len() > 18 || parse_i64(s.as_bytes()).is_none(), "{s:?}");
            }
        }
    }
}
