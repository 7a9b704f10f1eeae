//! The split stream: exact topology after decoding, positions within the
//! stated grid bound, incremental decoding in arbitrary pieces, typed errors
//! (never panics) on random and truncated bytes, and the size target on the
//! bunny.

mod common;
use lodgen_pm::shapes::{cube, grid, icosphere, torus_knot};
use lodgen_pm::stream::{
    decode, decode_header, decode_with_attributes, encode, encode_with_attributes, AttrEncoding,
    Channel, EncodeError, EncodeOptions, Grid, StreamDecoder, StreamError, WedgeAttributes,
    BLOCK_RECORDS,
};
use lodgen_pm::{simplify, simplify_with_wedges, Mesh, ProgressiveMesh, SimplifyOptions, Tau};
use proptest::prelude::*;

fn pm_of(mesh: &Mesh, opts: SimplifyOptions) -> ProgressiveMesh {
    simplify(&mesh.positions, &mesh.indices(), &opts)
        .expect("valid mesh")
        .pm
}

fn bound(pm: &ProgressiveMesh, bytes: &[u8]) -> f64 {
    let h = decode_header(bytes).expect("header");
    assert_eq!(h.split_count, pm.len());
    h.error_bound()
}

/// Every level's positions in `dec` are `pm`'s quantized on `grid`,
/// exactly, and within the grid's bound of the originals.
fn assert_level_positions(pm: &ProgressiveMesh, dec: &ProgressiveMesh, k: usize, grid: &Grid) {
    let want = pm.mesh_at_splits(k);
    let got = dec.mesh_at_splits(k);
    assert_eq!(want.positions.len(), got.positions.len());
    let b = grid.error_bound();
    for (v, (p, q)) in want.positions.iter().zip(&got.positions).enumerate() {
        assert_eq!(
            grid.dequantize(grid.quantize(*p)),
            *q,
            "k = {k}, vertex {v}"
        );
        for i in 0..3 {
            let err = (f64::from(p[i]) - f64::from(q[i])).abs();
            let slack = f64::from(p[i].abs().max(q[i].abs())) * f64::from(f32::EPSILON);
            assert!(
                err <= b * (1.0 + 1e-9) + slack,
                "k = {k}, vertex {v}, axis {i}: {p:?} vs {q:?}, bound {b}"
            );
        }
    }
}

/// For every k the same triangles exactly; at every level (chunk end) the
/// positions of the original quantized on the grid.
fn assert_round_trip(pm: &ProgressiveMesh, opts: EncodeOptions) {
    let levels = [pm.len(), pm.len() / 2, 0];
    let bytes = encode(pm, &levels, opts);
    let h = decode_header(&bytes).expect("header");
    assert_eq!(h.split_count, pm.len());
    let (dec, lv) = decode(&bytes).expect("decodes");
    assert_eq!(lv, levels);
    assert_eq!(dec.len(), pm.len());
    let mut a = pm.cursor();
    let mut d = dec.cursor();
    for k in 0..=pm.len() {
        assert_eq!(
            a.mesh().triangles,
            d.mesh().triangles,
            "triangles at k = {k}"
        );
        assert_eq!(a.mesh().positions.len(), d.mesh().positions.len());
        a.refine(1);
        d.refine(1);
    }
    for c in &h.chunks {
        assert_level_positions(pm, &dec, c.records, &h.grid);
    }
    // coarsening the decoded mesh walks back through the same topology
    let mut d = dec.cursor();
    d.seek(dec.len());
    for k in (0..=dec.len()).rev().step_by(7) {
        d.seek(k);
        assert_eq!(
            d.mesh().triangles,
            pm.mesh_at_splits(k).triangles,
            "coarsen to {k}"
        );
    }
}

/// Corner-edit bits the stream stores explicitly (the records whose edits
/// the arc prediction misses).
fn mask_bits(bytes: &[u8]) -> usize {
    let stats = lodgen_pm::stream::column_stats(bytes).expect("columns");
    stats
        .iter()
        .find(|s| s.name == "mask")
        .map_or(0, |s| s.count)
}

#[test]
fn icosphere_round_trips_exactly_in_topology() {
    let pm = pm_of(
        &icosphere(3),
        SimplifyOptions::DEFAULT.with_target_triangles(8),
    );
    assert!(pm.len() > 100);
    assert_round_trip(&pm, EncodeOptions::DEFAULT);
    // a closed manifold: the arc prediction gets nearly every split's
    // corner edits (fails when the prediction takes the wrong arc)
    let bytes = encode(&pm, &[pm.len()], EncodeOptions::DEFAULT);
    assert!(
        mask_bits(&bytes) < pm.len(),
        "{} mask bits",
        mask_bits(&bytes)
    );
}

#[test]
fn open_grid_with_borders_round_trips() {
    let m = grid(20, 15, |x, y| (x * 6.0).sin() * (y * 4.0).cos() * 0.1);
    let pm = pm_of(&m, SimplifyOptions::DEFAULT.with_target_triangles(4));
    assert_round_trip(&pm, EncodeOptions::DEFAULT.with_bits(12));
}

#[test]
fn tau_pairs_with_faceless_splits_round_trip() {
    // two boxes close together: τ-pairs join them with splits restoring no face
    let mut m = cube([0.0; 3], [1.0; 3], 3);
    let other = cube([1.02, 0.0, 0.0], [2.0, 1.0, 1.0], 3);
    let off = m.positions.len() as u32;
    m.positions.extend_from_slice(&other.positions);
    m.triangles
        .extend(other.triangles.iter().map(|t| t.map(|v| v + off)));
    let pm = pm_of(
        &m,
        SimplifyOptions::DEFAULT
            .with_target_triangles(4)
            .with_tau(Tau::Absolute(0.05)),
    );
    assert_round_trip(&pm, EncodeOptions::DEFAULT);
    // faceless splits move corners no wing predicts: the explicit
    // corner-edit path is taken (and replays exactly, above)
    assert!(mask_bits(&encode(&pm, &[pm.len()], EncodeOptions::DEFAULT)) > 0);
}

#[test]
fn errors_are_kept_only_when_asked() {
    let pm = pm_of(
        &icosphere(2),
        SimplifyOptions::DEFAULT.with_target_triangles(8),
    );
    let with = encode(&pm, &[], EncodeOptions::DEFAULT.with_errors(true));
    let without = encode(&pm, &[], EncodeOptions::DEFAULT);
    assert!(with.len() > without.len());
    let (d, _) = decode(&with).unwrap();
    let errors: Vec<f32> = d.splits.iter().map(|s| s.error).collect();
    assert_eq!(
        errors,
        pm.splits.iter().map(|s| s.error).collect::<Vec<_>>()
    );
    let (d, _) = decode(&without).unwrap();
    assert!(d.splits.iter().all(|s| s.error == 0.0));
}

#[test]
fn finer_grids_shrink_the_error_bound() {
    let pm = pm_of(
        &icosphere(2),
        SimplifyOptions::DEFAULT.with_target_triangles(8),
    );
    let coarse = bound(&pm, &encode(&pm, &[], EncodeOptions::DEFAULT.with_bits(8)));
    let fine = bound(&pm, &encode(&pm, &[], EncodeOptions::DEFAULT.with_bits(16)));
    // the icosphere spans at least [-1, 1] (intermediate placements may lie
    // outside): half ≥ 1, step = half / (2^(bits-1) - 1), bound = step / 2
    assert!((1.0 / 254.0..1.2 / 254.0).contains(&coarse), "{coarse}");
    let ratio = coarse / fine;
    assert!((ratio / (32767.0 / 127.0) - 1.0).abs() < 1e-6, "{ratio}");
    assert_round_trip(&pm, EncodeOptions::DEFAULT.with_bits(8));
}

#[test]
fn incremental_decoding_matches_one_shot_for_every_chunk_size() {
    let pm = pm_of(
        &icosphere(2),
        SimplifyOptions::DEFAULT.with_target_triangles(12),
    );
    let bytes = encode(&pm, &[3, pm.len()], EncodeOptions::DEFAULT);
    let (whole, _) = decode(&bytes).unwrap();
    for chunk in [1, 2, 3, 5, 16, 100, bytes.len()] {
        let mut d = StreamDecoder::new();
        let mut seen = 0;
        let mut records_before_end = 0;
        for (i, piece) in bytes.chunks(chunk).enumerate() {
            seen += d.push(piece).unwrap();
            assert_eq!(seen, d.splits().len());
            // records become available as their bytes arrive, not at the end
            if (i + 1) * chunk < bytes.len() {
                records_before_end = seen;
            }
            if let Some(base) = d.base() {
                assert_eq!(base, &whole.base);
                assert_eq!(d.mesh(), &whole.mesh_at_splits(seen));
            }
        }
        if chunk < bytes.len() / 2 {
            assert!(records_before_end > 0, "chunk {chunk}");
        }
        assert!(d.is_complete());
        assert_eq!(d.finish().unwrap().0, whole);
    }
}

#[test]
fn malformed_headers_are_typed_errors() {
    let pm = pm_of(
        &icosphere(1),
        SimplifyOptions::DEFAULT.with_target_triangles(8),
    );
    let bytes = encode(&pm, &[1], EncodeOptions::DEFAULT);
    assert_eq!(decode(b"GLTF...."), Err(StreamError::Magic));
    let mut v = bytes.clone();
    v[4] = 9;
    assert_eq!(decode(&v), Err(StreamError::Version(9)));
    let mut v = bytes.clone();
    v.push(0);
    assert_eq!(decode(&v), Err(StreamError::TrailingBytes(1)));
    assert!(matches!(
        decode(&bytes[..bytes.len() - 1]),
        Err(StreamError::Truncated(_))
    ));
    // a chunk whose length is off by one byte
    let h = decode_header(&bytes).unwrap();
    let mut v = bytes.clone();
    v.insert(h.chunk_offset(1), 0);
    assert!(matches!(decode(&v), Err(StreamError::Invalid { .. })));
}

fn sample_stream() -> Vec<u8> {
    let pm = pm_of(
        &torus_knot(2, 3, 24, 6, 0.01),
        SimplifyOptions::DEFAULT.with_target_triangles(16),
    );
    encode(&pm, &[0, 5, pm.len()], EncodeOptions::DEFAULT)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        let _ = decode(&bytes);
        let mut with_magic = b"LGPM\x02\x00\x10".to_vec();
        with_magic.extend_from_slice(&bytes);
        let _ = decode(&with_magic);
    }

    #[test]
    fn truncated_and_corrupted_streams_are_errors(cut in 0usize..10_000, flip in 0usize..10_000, bit in 0u8..8) {
        let bytes = sample_stream();
        let cut = cut % bytes.len();
        prop_assert!(decode(&bytes[..cut]).is_err());
        let mut v = bytes.clone();
        let at = flip % v.len();
        v[at] ^= 1 << bit;
        // a flipped bit may still decode (e.g. a position delta); it must
        // not panic, and what it yields must replay without panicking
        if let Ok((pm, _)) = decode(&v) {
            let mut c = pm.cursor();
            c.refine(pm.len());
            c.coarsen(pm.len());
        }
        let mut d = StreamDecoder::new();
        for piece in v.chunks(1 + at % 13) {
            if d.push(piece).is_err() {
                break;
            }
        }
    }
}

/// The size figures of the issue, on the bunny (skipped when the shared
/// asset is absent). Run with `--nocapture` to see them.
#[test]
fn bunny_stream_is_within_the_size_target() {
    let Some(text) = common::shared_asset_text("bunny.obj") else {
        return;
    };
    let (positions, indices) = common::read_obj(&text);
    let out = simplify(
        &positions,
        &indices,
        &SimplifyOptions::DEFAULT.with_target_ratio(0.02),
    )
    .unwrap();
    let pm = out.pm;
    let levels = [
        lodgen_pm::levels::splits_for(&pm, lodgen_pm::levels::LevelSpec::Ratio(1.0)),
        lodgen_pm::levels::splits_for(&pm, lodgen_pm::levels::LevelSpec::Ratio(0.5)),
        lodgen_pm::levels::splits_for(&pm, lodgen_pm::levels::LevelSpec::Ratio(0.1)),
        0,
    ];
    let bytes = encode(&pm, &levels, EncodeOptions::DEFAULT);
    let h = decode_header(&bytes).unwrap();
    let fine = pm.mesh_at_splits(pm.len());
    let (nv, nt) = (fine.positions.len(), fine.triangles.len());
    // the finest level alone, coded as lodgen's `--quantize --compress
    // meshopt` codes it (positions only): vertex cache + fetch order, i16×4
    // positions on the same grid through the vertex codec (version 0),
    // indices through the triangle codec
    let full = {
        let flat: Vec<u32> = fine.triangles.iter().flatten().copied().collect();
        let mut idx = meshopt::optimize_vertex_cache(&flat, nv);
        let mut pos = fine.positions.clone();
        let n = meshopt::optimize_vertex_fetch_in_place(&mut idx, &mut pos);
        let q: Vec<[u16; 4]> = pos[..n]
            .iter()
            .map(|p| {
                let q = h.grid.quantize(*p);
                [q[0], q[1], q[2], 0]
            })
            .collect();
        meshopt::encode_vertex_buffer_level(&q, 2, Some(0))
            .unwrap()
            .len()
            + meshopt::encode_index_buffer(&idx, n).unwrap().len()
    };
    eprintln!(
        "bunny: {nv} vertices, {nt} triangles; base {} v / {} t; {} splits",
        pm.base.positions.len(),
        pm.base.triangles.len(),
        pm.len()
    );
    eprintln!(
        "stream {} B = header {} B + base {} B + records {} B ({:.2} B/split); \
         full mesh meshopt-coded (positions + indices) {full} B: ratio {:.3}; grid bound {:.3e} (diag {:.3})",
        bytes.len(),
        h.header_bytes,
        h.chunks[0].bytes,
        bytes.len() - h.chunk_offset(1),
        (bytes.len() - h.chunk_offset(1)) as f64 / pm.len() as f64,
        bytes.len() as f64 / full as f64,
        h.error_bound(),
        fine.diagonal(),
    );
    // v1 was 1.03 MB, 4.3× this reference; v2 is ~1.7× (the glTF file
    // comparison with normals, which the client computes, is in
    // docs/LODGEN_progressive.md)
    assert!(bytes.len() as f64 <= 2.0 * full as f64);
    let (dec, lv) = decode(&bytes).unwrap();
    assert_eq!(lv, levels);
    for &k in &levels {
        assert_eq!(
            dec.mesh_at_splits(k).triangles,
            pm.mesh_at_splits(k).triangles
        );
        assert_level_positions(&pm, &dec, k, &h.grid);
    }
}

// ------------------------------------------------------------ wedges

/// An icosphere cut into its eight octants as charts: each octant has its
/// own copy of the vertices on its border (UV seams), a normal and a
/// chart-dependent UV per copy; octants alternate between two groups when
/// `grouped`. Returns positions, indices, and the attributes per vertex.
fn charted_sphere(subdivisions: u32, grouped: bool) -> (Vec<[f32; 3]>, Vec<u32>, WedgeAttributes) {
    let m = icosphere(subdivisions);
    let mut ids = std::collections::BTreeMap::new();
    let (mut pos, mut idx, mut values, mut groups) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for tri in &m.triangles {
        let c: [f32; 3] = [0, 1, 2].map(|a| tri.iter().map(|&v| m.positions[v as usize][a]).sum());
        let chart = u32::from(c[0] > 0.0) | u32::from(c[1] > 0.0) << 1 | u32::from(c[2] > 0.0) << 2;
        for &v in tri {
            let id = *ids.entry((chart, v)).or_insert_with(|| {
                let p = m.positions[v as usize];
                let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                pos.push(p);
                values.extend_from_slice(&[p[0] / n, p[1] / n, p[2] / n]);
                values.extend_from_slice(&[
                    0.1 * chart as f32 + 0.05 * p[0] + 0.05,
                    0.5 + 0.3 * p[1] - 0.2 * p[2],
                ]);
                groups.push(if grouped { chart % 2 } else { 0 });
                pos.len() as u32 - 1
            });
            idx.push(id);
        }
    }
    let count = pos.len();
    let attrs = WedgeAttributes {
        channels: vec![
            Channel {
                name: "NORMAL".into(),
                components: 3,
            },
            Channel {
                name: "TEXCOORD_0".into(),
                components: 2,
            },
        ],
        values,
        groups: if grouped { groups } else { Vec::new() },
        count,
    };
    (pos, idx, attrs)
}

fn wedged(subdivisions: u32, grouped: bool, target: usize) -> (ProgressiveMesh, WedgeAttributes) {
    let (pos, idx, attrs) = charted_sphere(subdivisions, grouped);
    let pm = simplify_with_wedges(
        &pos,
        &idx,
        &attrs.values,
        attrs.stride(),
        &SimplifyOptions::DEFAULT.with_target_triangles(target),
    )
    .expect("valid mesh")
    .pm;
    (pm, attrs)
}

/// `a` with every value through its channel's encoding (what a stream
/// with those encodings carries).
fn round_tripped(a: &WedgeAttributes, encodings: &[AttrEncoding]) -> WedgeAttributes {
    let stride = a.stride();
    let mut lanes = Vec::new();
    for (c, e) in a.channels.iter().zip(encodings) {
        lanes.extend(std::iter::repeat_n(*e, usize::from(c.components)));
    }
    let values = a
        .values
        .iter()
        .enumerate()
        .map(|(i, &x)| lanes[i % stride].round_trip(x))
        .collect();
    WedgeAttributes {
        values,
        ..a.clone()
    }
}

/// Every corner of `a` (log numbering, values in `va`) and `b` (stream
/// numbering, values in `vb`) has bit-identical attribute values and group.
fn assert_same_corner_values(
    k: usize,
    a: (&[[u32; 3]], &WedgeAttributes),
    b: (&[[u32; 3]], &WedgeAttributes),
) {
    assert_eq!(a.0.len(), b.0.len(), "corner count at k = {k}");
    for (t, (wa, wb)) in a.0.iter().zip(b.0).enumerate() {
        for s in 0..3 {
            let (x, y) = (a.1.wedge(wa[s]), b.1.wedge(wb[s]));
            assert!(
                x.iter().zip(y).all(|(p, q)| p.to_bits() == q.to_bits()),
                "k = {k}, triangle {t} corner {s}: {x:?} vs {y:?}"
            );
            assert_eq!(
                a.1.group(wa[s]),
                b.1.group(wb[s]),
                "group at k = {k}, triangle {t}"
            );
        }
    }
}

#[test]
fn wedged_stream_replays_every_corner_attribute_exactly() {
    let cases = [
        (false, false, false),
        (true, false, false),
        (false, true, false),
        (false, false, true),
    ];
    for (grouped, exact, shifted) in cases {
        let (pm, mut attrs) = wedged(3, grouped, 24);
        assert!(pm.len() > 200);
        // `shifted`: UVs spread over [-0.5, 1.5] (leaving [0, 1], as spot's
        // do), stored as unorm16 over their range
        let stride = attrs.stride();
        if shifted {
            for w in attrs.values.chunks_exact_mut(stride) {
                for x in &mut w[3..5] {
                    *x = *x * 2.0 - 0.5;
                }
            }
        }
        let uvs = || attrs.values.chunks_exact(stride).flat_map(|w| [w[3], w[4]]);
        let (lo, hi) = uvs().fold((f32::MAX, f32::MIN), |(l, h), x| (l.min(x), h.max(x)));
        let levels = [pm.len(), pm.len() / 3, 0];
        let opts = EncodeOptions::DEFAULT.with_exact_attributes(exact);
        let bytes = encode_with_attributes(&pm, &levels, opts, &attrs).unwrap();
        let plain = encode(&pm, &levels, EncodeOptions::DEFAULT);
        assert!(bytes.len() > plain.len());
        let h = decode_header(&bytes).unwrap();
        let layout = h.wedges.expect("wedge table");
        assert_eq!(layout.channels, attrs.channels);
        assert_eq!(layout.groups, if grouped { 2 } else { 1 });
        // normals as snorm8 and UVs (all in [0, 1]) as unorm16, as
        // `--quantize` writes them; or exact f32
        let want = if exact {
            vec![AttrEncoding::F32; 2]
        } else if shifted {
            let AttrEncoding::Unorm16Range(r) = layout.encodings[1] else {
                panic!("shifted UVs as {:?}", layout.encodings[1]);
            };
            // the range is the values' span: from the least, just reaching
            // the greatest
            assert!(lo < 0.0 && hi > 1.0, "{lo} {hi}");
            assert_eq!(r.offset, lo);
            assert!(f64::from(r.offset) + f64::from(r.scale) >= f64::from(hi));
            let below = f32::from_bits(r.scale.to_bits() - 1);
            assert!(f64::from(r.offset) + f64::from(below) < f64::from(hi));
            // within half a step of 1/65535 of the range
            for x in uvs() {
                let e = layout.encodings[1];
                let err = (f64::from(e.round_trip(x)) - f64::from(x)).abs();
                assert!(
                    err <= f64::from(r.scale) / 65535.0 * 0.5 + 1e-7,
                    "{x}: {err}"
                );
            }
            // a header whose range is not finite or not positive is refused
            let mut key = vec![4u8];
            key.extend(r.offset.to_le_bytes());
            key.extend(r.scale.to_le_bytes());
            let at = bytes.windows(9).position(|w| w == key).expect("the range") + 5;
            for bad in [0.0f32, -1.0, f32::NAN, f32::INFINITY] {
                let mut b = bytes.clone();
                b[at..at + 4].copy_from_slice(&bad.to_le_bytes());
                let e = decode_header(&b).expect_err("a bad range");
                assert!(e.to_string().contains("attribute range"), "{e}");
            }
            vec![AttrEncoding::Snorm8, AttrEncoding::Unorm16Range(r)]
        } else {
            vec![AttrEncoding::Snorm8, AttrEncoding::Unorm16]
        };
        assert_eq!(layout.encodings, want);
        let expected = round_tripped(&attrs, &want);
        assert_eq!(exact, expected == attrs);
        let dec = decode_with_attributes(&bytes).unwrap();
        assert_eq!(dec.levels, levels);
        let got = dec.attributes.as_ref().expect("attributes decoded");
        assert_eq!(got.count, layout.total);
        // the plain decoder sees the same topology
        assert_eq!(decode(&bytes).unwrap().0.splits.len(), pm.len());
        let (mut a, mut d) = (pm.cursor(), dec.pm.cursor());
        for k in 0..=pm.len() {
            assert_eq!(a.mesh().triangles, d.mesh().triangles, "k = {k}");
            assert_same_corner_values(
                k,
                (a.wedges().unwrap(), &expected),
                (d.wedges().unwrap(), got),
            );
            a.refine(1);
            d.refine(1);
        }
        // and back down: the decoded log's "before" wedges undo every edit
        for k in (0..=pm.len()).rev().step_by(5) {
            a.seek(k);
            d.seek(k);
            assert_same_corner_values(
                k,
                (a.wedges().unwrap(), &expected),
                (d.wedges().unwrap(), got),
            );
        }
    }
}

#[test]
fn fully_refined_stream_has_the_input_attributes_at_every_corner() {
    let (pos, idx, attrs) = charted_sphere(2, true);
    let out = simplify_with_wedges(
        &pos,
        &idx,
        &attrs.values,
        attrs.stride(),
        &SimplifyOptions::DEFAULT.with_target_triangles(10),
    )
    .unwrap();
    let bytes = encode_with_attributes(&out.pm, &[0], EncodeOptions::DEFAULT, &attrs).unwrap();
    let dec = decode_with_attributes(&bytes).unwrap();
    let got = dec.attributes.as_ref().unwrap();
    let encodings = decode_header(&bytes).unwrap().wedges.unwrap().encodings;
    let attrs = round_tripped(&attrs, &encodings);
    // topology is exact: the in-memory full mesh has the decoded triangles,
    // with unquantized positions to find each input corner by
    let fine = out.pm.mesh_at_splits(out.pm.len());
    assert_eq!(
        fine.triangles,
        dec.pm.mesh_at_splits(dec.pm.len()).triangles
    );
    let mut c = dec.pm.cursor();
    c.seek(dec.pm.len());
    let wedges = c.wedges().unwrap();
    // every input triangle appears (as origin), with its corners' values
    for (t, origin) in out.pm.triangle_origin.iter().enumerate() {
        let input = out.triangle_map[*origin as usize] as usize;
        let input = &idx[3 * input..][..3];
        let tri = fine.triangles[t];
        for s in 0..3 {
            // the same corner, found by position (rotation kept by the log)
            let p = fine.positions[tri[s] as usize];
            let k = (0..3)
                .find(|&j| pos[input[j] as usize] == p)
                .expect("corner");
            assert_eq!(
                got.wedge(wedges[t][s]),
                attrs.wedge(input[k]),
                "triangle {t}"
            );
            assert_eq!(got.group(wedges[t][s]), attrs.group(input[k]));
        }
    }
}

#[test]
fn incremental_wedged_decoding_shows_each_step() {
    let (pm, attrs) = wedged(2, true, 12);
    let bytes =
        encode_with_attributes(&pm, &[pm.len(), 0], EncodeOptions::DEFAULT, &attrs).unwrap();
    let whole = decode_with_attributes(&bytes).unwrap();
    let encodings = decode_header(&bytes).unwrap().wedges.unwrap().encodings;
    let attrs = round_tripped(&attrs, &encodings);
    for chunk in [1, 3, 64, bytes.len()] {
        let mut d = StreamDecoder::new();
        let mut a = pm.cursor();
        for piece in bytes.chunks(chunk) {
            d.push(piece).unwrap();
            if d.base().is_some() {
                a.seek(d.splits().len());
                assert_same_corner_values(
                    d.splits().len(),
                    (a.wedges().unwrap(), &attrs),
                    (d.wedges().unwrap(), d.attributes().unwrap()),
                );
            }
        }
        assert_eq!(d.finish_with_attributes().unwrap(), whole);
    }
}

/// A level step longer than a block: its topology and wedge columns in
/// several blocks (version 7), decoded exactly, whole and in pieces that
/// cut the blocks anywhere.
#[test]
fn chunks_of_several_blocks_round_trip() {
    let (pm, attrs) = wedged(6, true, 400);
    let (len, third) = (pm.len(), pm.len() / 3);
    assert!(len - third > 2 * BLOCK_RECORDS, "{len} splits");
    let levels = [len, third, 0];
    let plain = encode(&pm, &levels, EncodeOptions::DEFAULT);
    let h = decode_header(&plain).unwrap();
    assert_eq!(h.chunks.len(), 3);
    let (dec, _) = decode(&plain).unwrap();
    for k in (0..=len).step_by(997).chain([third, len]) {
        assert_eq!(
            dec.mesh_at_splits(k).triangles,
            pm.mesh_at_splits(k).triangles,
            "k = {k}"
        );
    }
    for c in &h.chunks {
        assert_level_positions(&pm, &dec, c.records, &h.grid);
    }
    // the blocks' columns, then the positions: one `v1` value per record
    let stats = lodgen_pm::stream::column_stats(&plain).unwrap();
    let v1 = stats.iter().find(|s| s.name == "v1").unwrap();
    assert_eq!(v1.count, len);
    let bytes = encode_with_attributes(&pm, &levels, EncodeOptions::DEFAULT, &attrs).unwrap();
    let whole = decode_with_attributes(&bytes).unwrap();
    let encodings = decode_header(&bytes).unwrap().wedges.unwrap().encodings;
    let attrs = round_tripped(&attrs, &encodings);
    let decoded = whole.attributes.as_ref().unwrap();
    let (mut a, mut d) = (pm.cursor(), whole.pm.cursor());
    for k in [third, len] {
        a.seek(k);
        d.seek(k);
        assert_same_corner_values(
            k,
            (a.wedges().unwrap(), &attrs),
            (d.wedges().unwrap(), decoded),
        );
    }
    let mut d = StreamDecoder::new();
    for piece in bytes.chunks(4093) {
        d.push(piece).unwrap();
    }
    assert_eq!(d.finish_with_attributes().unwrap(), whole);
}

#[test]
fn encoding_attributes_checks_its_input() {
    let (pm, attrs) = wedged(1, false, 8);
    let plain = pm_of(
        &icosphere(1),
        SimplifyOptions::DEFAULT.with_target_triangles(8),
    );
    assert_eq!(
        encode_with_attributes(&plain, &[0], EncodeOptions::DEFAULT, &attrs),
        Err(EncodeError::NoWedges)
    );
    let mut short = attrs.clone();
    short.count -= 1;
    short.values.truncate(short.count * short.stride());
    assert!(matches!(
        encode_with_attributes(&pm, &[0], EncodeOptions::DEFAULT, &short),
        Err(EncodeError::WedgeOutOfRange { .. })
    ));
    let mut ragged = attrs.clone();
    ragged.values.pop();
    assert!(matches!(
        encode_with_attributes(&pm, &[0], EncodeOptions::DEFAULT, &ragged),
        Err(EncodeError::Values { .. })
    ));
    let mut unnamed = attrs.clone();
    unnamed.channels[0].name.clear();
    assert!(matches!(
        encode_with_attributes(&pm, &[0], EncodeOptions::DEFAULT, &unnamed),
        Err(EncodeError::Channel { index: 0, .. })
    ));
    let mut groups = attrs;
    groups.groups = vec![0; 3];
    assert!(matches!(
        encode_with_attributes(&pm, &[0], EncodeOptions::DEFAULT, &groups),
        Err(EncodeError::Groups { .. })
    ));
}

fn wedged_sample_stream() -> Vec<u8> {
    let (pm, attrs) = wedged(1, true, 8);
    encode_with_attributes(
        &pm,
        &[0, 3, pm.len()],
        EncodeOptions::DEFAULT.with_errors(true),
        &attrs,
    )
    .unwrap()
}

#[test]
fn every_truncation_of_a_wedged_stream_is_an_error() {
    let bytes = wedged_sample_stream();
    assert!(decode_with_attributes(&bytes).is_ok());
    for cut in 0..bytes.len() {
        assert!(
            matches!(
                decode_with_attributes(&bytes[..cut]),
                Err(StreamError::Truncated(_))
            ),
            "cut at {cut}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn corrupted_wedged_streams_never_panic(flip in 0usize..100_000, bit in 0u8..8) {
        let mut v = wedged_sample_stream();
        let at = flip % v.len();
        v[at] ^= 1 << bit;
        if let Ok(d) = decode_with_attributes(&v) {
            let mut c = d.pm.cursor();
            c.refine(d.pm.len());
            let a = d.attributes.unwrap();
            for w in c.wedges().unwrap().iter().flatten() {
                prop_assert!((*w as usize) < a.count);
                let _ = a.wedge(*w);
            }
            c.coarsen(d.pm.len());
        }
    }
}

#[test]
fn splits_restoring_three_or_four_faces_round_trip() {
    // fins sharing a chain of non-manifold edges: splits restore k faces,
    // whose codes past the second go to the escape column and whose corner
    // edits the arc prediction may miss (fails if the decoder read two
    // faces per record at most, or the encoder dropped the others)
    for k in [3, 4] {
        let m = common::fins(k, 8, 3, 0.3, 0.02, 11);
        let pm = pm_of(&m, SimplifyOptions::DEFAULT.with_target_triangles(0));
        assert!(pm.splits.iter().any(|s| s.faces.len() == k as usize));
        assert_round_trip(&pm, EncodeOptions::DEFAULT);
    }
}

/// Splits of contractions `SimplifyOptions::allow_topology_change` let
/// through (a closed sphere flattened into two coinciding faces, beetle's
/// panels joined across its border loops) code and decode exactly like any
/// other: fails if the stream assumed a manifold ring around each split.
#[test]
fn topology_changing_splits_round_trip() {
    let opts = |target| {
        SimplifyOptions::DEFAULT
            .with_target_triangles(target)
            .with_allow_topology_change(true)
    };
    let pm = pm_of(&icosphere(1), opts(2));
    assert_eq!(pm.base.triangles.len(), 2);
    assert_round_trip(&pm, EncodeOptions::DEFAULT);
    if let Some(m) = common::shared_mesh("beetle.obj") {
        let out = simplify(&m.positions, &m.indices(), &opts(41)).unwrap();
        assert!(out.stats.relaxed.total() > 0);
        assert_round_trip(&out.pm, EncodeOptions::DEFAULT);
    }
}
