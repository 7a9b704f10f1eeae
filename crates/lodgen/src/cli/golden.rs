//! The golden summary of LOD builds (`assets/golden/*.txt`).

use crate::lod::MeshBuild;

/// FNV-1a, 64 bit: a small, stable hash for golden summaries.
fn fnv1a(hash: &mut u64, bytes: &[u8]) {
    for &b in bytes {
        *hash ^= u64::from(b);
        *hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
    }
}

/// The golden summary of LOD builds (`assets/golden/*.txt`): per level the
/// triangle and vertex counts, measured errors, and a hash of the index data
/// and of the positions quantized to 2⁻¹⁶ of the bounding-box diagonal.
pub fn golden_summary(title: &str, builds: &[MeshBuild]) -> String {
    let mut s = format!(
        "# lodgen golden summary: {title}\n# regenerate with `cargo xtask golden` and commit\n"
    );
    for b in builds {
        let full = b.simplified.pm.mesh_at_splits(b.simplified.pm.len());
        let (lo, _) = full.bounds().unwrap_or(([0.0; 3], [0.0; 3]));
        let diag = full.diagonal().max(f64::MIN_POSITIVE);
        s += &format!(
            "mesh {:?} welded_triangles {} welded_vertices {}\n",
            b.lod.name, b.simplified.stats.input_triangles, b.simplified.stats.input_vertices
        );
        for (k, (l, e)) in b.lod.levels.iter().zip(&b.errors).enumerate() {
            let mut h = 0xcbf2_9ce4_8422_2325u64;
            for p in &l.primitives {
                for i in &p.indices {
                    fnv1a(&mut h, &i.to_le_bytes());
                }
                for v in &p.positions {
                    for c in 0..3 {
                        let q =
                            ((f64::from(v[c]) - f64::from(lo[c])) / diag * 65536.0).round() as i64;
                        fnv1a(&mut h, &q.to_le_bytes());
                    }
                }
            }
            s += &format!(
                "level {k} triangles {} vertices {} hausdorff_percent {:.6} rms_percent {:.6} hash {h:016x}\n",
                l.triangle_count(),
                l.primitives.iter().map(|p| p.positions.len()).sum::<usize>(),
                e.hausdorff_percent(),
                e.rms_percent(),
            );
        }
    }
    s
}
