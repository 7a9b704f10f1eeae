//! The byte-level pieces of the glTF reader: component sizes and element
//! decoding, strips and fans unrolled, base64 `data:` URIs and `%XX`
//! escapes. Pure functions, no document.

use gltf::json::accessor::ComponentType;

pub(super) fn component_size(ct: ComponentType) -> usize {
    match ct {
        ComponentType::I8 | ComponentType::U8 => 1,
        ComponentType::I16 | ComponentType::U16 => 2,
        ComponentType::U32 | ComponentType::F32 => 4,
    }
}

/// Decodes one little-endian element of `out.len() == dims` components.
/// `data` must hold at least one element (checked by `Reader::view`).
pub(super) fn read_element(
    data: &[u8],
    ct: ComponentType,
    dims: usize,
    normalized: bool,
    out: &mut [f64],
) {
    let size = component_size(ct);
    debug_assert!(data.len() >= size * dims);
    for (k, slot) in out.iter_mut().enumerate().take(dims) {
        let b = &data[k * size..(k + 1) * size];
        *slot = match ct {
            ComponentType::I8 => {
                let v = b[0] as i8 as f64;
                if normalized {
                    (v / 127.0).max(-1.0)
                } else {
                    v
                }
            }
            ComponentType::U8 => {
                let v = b[0] as f64;
                if normalized {
                    v / 255.0
                } else {
                    v
                }
            }
            ComponentType::I16 => {
                let v = i16::from_le_bytes([b[0], b[1]]) as f64;
                if normalized {
                    (v / 32767.0).max(-1.0)
                } else {
                    v
                }
            }
            ComponentType::U16 => {
                let v = u16::from_le_bytes([b[0], b[1]]) as f64;
                if normalized {
                    v / 65535.0
                } else {
                    v
                }
            }
            ComponentType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            ComponentType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        };
    }
}

/// glTF triangle strip to list: triangle `i` is
/// `(v[i], v[i + 1 + i % 2], v[i + 2 - i % 2])` (glTF 2.0 §3.7.2.1).
pub(super) fn strip_to_list(v: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(v.len().saturating_sub(2) * 3);
    for i in 0..v.len().saturating_sub(2) {
        out.extend_from_slice(&[v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]]);
    }
    out
}

/// glTF triangle fan to list: triangle `i` is `(v[i + 1], v[i + 2], v[0])`.
pub(super) fn fan_to_list(v: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(v.len().saturating_sub(2) * 3);
    for i in 0..v.len().saturating_sub(2) {
        out.extend_from_slice(&[v[i + 1], v[i + 2], v[0]]);
    }
    out
}

/// Standard base64 with padding (for `data:` URIs).
pub fn encode_base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for k in 0..4 {
            out.push(if k <= chunk.len() {
                A[(n >> (18 - 6 * k) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    out
}

/// Standard base64 (padding optional); `None` on any invalid character.
pub(crate) fn decode_base64(s: &str) -> Option<Vec<u8>> {
    let s = s.trim_end_matches('=');
    let mut out = Vec::with_capacity(s.len() * 3 / 4);
    let mut acc = 0u32;
    let mut bits = 0;
    for c in s.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        };
        acc = (acc << 6) | v as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

/// Decodes `%XX` escapes of a relative URI; `None` if malformed.
pub(super) fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_values() {
        assert_eq!(decode_base64("TWFu").as_deref(), Some(&b"Man"[..]));
        assert_eq!(decode_base64("TWE=").as_deref(), Some(&b"Ma"[..]));
        assert_eq!(decode_base64("TQ==").as_deref(), Some(&b"M"[..]));
        assert_eq!(decode_base64("T!=="), None);
        for s in [&b"Man"[..], b"Ma", b"M", b"", b"\x00\xff\x10lodgen"] {
            assert_eq!(decode_base64(&encode_base64(s)).as_deref(), Some(s));
        }
        assert_eq!(encode_base64(b"Ma"), "TWE=");
    }

    #[test]
    fn strip_and_fan_follow_the_spec() {
        assert_eq!(
            strip_to_list(&[0, 1, 2, 3, 4]),
            vec![0, 1, 2, 1, 3, 2, 2, 3, 4]
        );
        assert_eq!(fan_to_list(&[0, 1, 2, 3]), vec![1, 2, 0, 2, 3, 0]);
        assert!(strip_to_list(&[0, 1]).is_empty());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(percent_decode("a%2"), None);
        assert_eq!(percent_decode("%FF"), None);
    }
}
