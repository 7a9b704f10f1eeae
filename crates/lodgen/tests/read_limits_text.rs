//! The memory cap (`lodgen::io::DECODED_BYTES_PER_INPUT_BYTE`) for the text
//! formats, which declare no counts: OBJ and SMF arrays grow with the lines
//! read, so what they allocate is bounded by the file's length. Each case is
//! a file built to make the reader allocate the most per input byte (tiny
//! vertex lines, huge polygons, an object or material per face, many
//! distinct corners); its peak allocation while reading (a counting
//! allocator, per thread) must stay within half the cap *without* the
//! floor, except an object per face, which costs one `Primitive` each (about
//! 60 bytes per input byte): there the bound is per object.

mod support;

use std::fmt::Write as _;
use std::path::Path;

use lodgen::io::{read_obj, read_smf, DECODED_BYTES_PER_INPUT_BYTE};
use support::alloc::peak_of;

#[global_allocator]
static ALLOCATOR: support::alloc::Counting = support::alloc::Counting;

/// About this many bytes per case: enough that fixed costs do not matter.
const SIZE: usize = 1 << 18;

/// Repeats `unit(i)` until the text reaches [`SIZE`].
fn file(head: &str, mut unit: impl FnMut(usize, &mut String)) -> String {
    let mut s = head.to_owned();
    let mut i = 0;
    while s.len() < SIZE {
        unit(i, &mut s);
        i += 1;
    }
    s
}

type Reader = fn(&[u8], &Path) -> Result<lodgen::scene::Scene, lodgen::io::ReadError>;

/// Reads `text` with `read` and checks the peak: at most half the cap per
/// input byte, or, with one mesh per `per_mesh` bytes, that many bytes per
/// mesh. Returns the bytes allocated per input byte.
fn per_byte(text: &str, read: Reader, what: &str, per_mesh: Option<usize>) -> f64 {
    let (scene, peak) = peak_of(|| read(text.as_bytes(), Path::new("cap.obj")));
    let scene = scene.unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(!scene.meshes.is_empty(), "{what}");
    let ratio = peak as f64 / text.len() as f64;
    let bound = match per_mesh {
        Some(b) => (b * scene.meshes.len()) as f64 / text.len() as f64,
        None => DECODED_BYTES_PER_INPUT_BYTE as f64 / 2.0,
    };
    assert!(
        ratio <= bound,
        "{what}: {peak} bytes allocated for {} input bytes ({ratio:.1} per byte, bound {bound:.1})",
        text.len()
    );
    ratio
}

#[test]
fn obj_reading_stays_within_the_memory_cap() {
    let cases = [
        // short vertex lines, one face using them all
        (
            "vertices",
            file("", |_, s| s.push_str("v 0 0 0\n"))
                + &{
                    let n = SIZE / 8;
                    let mut f = String::from("f");
                    for i in 1..=n.min(3 * (SIZE / 8)) {
                        let _ = write!(f, " {i}");
                    }
                    f + "\n"
                },
        ),
        // one huge polygon over three vertices: a fan of ~SIZE/2 triangles
        (
            "polygon",
            file("v 0 0 0\nv 1 0 0\nv 0 1 0\nf", |i, s| {
                s.push_str([" 1", " 2", " 3"][i % 3])
            }) + "\n",
        ),
        // an object per face
        (
            "objects",
            file("v 0 0 0\nv 1 0 0\nv 0 1 0\n", |_, s| {
                s.push_str("o\nf 1 2 3\n")
            }),
        ),
        // a new material per face (a primitive each)
        (
            "materials",
            file("v 0 0 0\nv 1 0 0\nv 0 1 0\n", |i, s| {
                let _ = writeln!(s, "usemtl {}\nf 1 2 3", i % 4096);
            }),
        ),
        // distinct corners: every vertex with every texture coordinate
        (
            "corners",
            file(
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvn 0 0 1\n",
                |i, s| {
                    let t = 1 + i % 2;
                    let _ = writeln!(s, "f 1/{t}/1 2/{t} 3//1");
                },
            ),
        ),
    ];
    // an object: its `Primitive` and at most 512 bytes more
    let per_object = std::mem::size_of::<lodgen::scene::Primitive>() + 512;
    for (what, text) in &cases {
        let per_mesh = (*what == "objects").then_some(per_object);
        let r = per_byte(text, read_obj, what, per_mesh);
        eprintln!("OBJ {what}: {r:.1} bytes per input byte");
    }
}

#[test]
fn smf_reading_stays_within_the_memory_cap() {
    let vertices = file("", |_, s| s.push_str("v 0 0 0\n")) + "f 1 2 3\n";
    let faces = file("v 0 0 0\nv 1 0 0\nv 0 1 0\n", |_, s| {
        s.push_str("f 1 2 3\n")
    });
    for (what, text) in [("vertices", vertices), ("faces", faces)] {
        let r = per_byte(&text, read_smf, what, None);
        eprintln!("SMF {what}: {r:.1} bytes per input byte");
    }
}
