//! The Python peers of `cargo xtask quality`: the venv, the script that
//! runs them, and the binary mesh files it reads and writes.

use anyhow::{Context, Result};
use lodgen_pm::Mesh;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The Python peers: (label, module to import, pip package).
pub(super) const PEERS: [(&str, &str, &str); 4] = [
    ("MeshLab", "pymeshlab", "pymeshlab"),
    ("Open3D", "open3d", "open3d"),
    ("pyfqmr", "pyfqmr", "pyfqmr"),
    ("fast-simpl.", "fast_simplification", "fast-simplification"),
];

/// Reads `IN.bin` (u32 vertex count, u32 triangle count, f32 xyz…, u32
/// abc…) and, for each target count given, writes one simplified mesh per
/// tool in the same format to `OUT-TOOL-COUNT.bin` (or nothing when the
/// tool fails, with the error on stderr).
const PEER_SCRIPT: &str = r#"
import sys, struct, numpy as np
src, out, tools = sys.argv[1], sys.argv[2], sys.argv[3].split(',')
counts = [int(c) for c in sys.argv[4:]]
b = open(src, 'rb').read()
nv, nt = struct.unpack('<II', b[:8])
v = np.frombuffer(b, '<f4', 3 * nv, 8).reshape(nv, 3).astype(np.float64)
f = np.frombuffer(b, '<u4', 3 * nt, 8 + 12 * nv).reshape(nt, 3).astype(np.int64)
def save(tool, n, pv, pf):
    pv = np.ascontiguousarray(pv, '<f4'); pf = np.ascontiguousarray(pf, '<u4')
    with open('%s-%s-%d.bin' % (out, tool, n), 'wb') as o:
        o.write(struct.pack('<II', len(pv), len(pf))); o.write(pv.tobytes()); o.write(pf.tobytes())
def meshlab(n):
    import pymeshlab
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=v, face_matrix=f.astype(np.int32)))
    ms.meshing_decimation_quadric_edge_collapse(targetfacenum=n)
    m = ms.current_mesh()
    return m.vertex_matrix(), m.face_matrix()
def open3d(n):
    import open3d as o3d
    m = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(v), o3d.utility.Vector3iVector(f.astype(np.int32)))
    r = m.simplify_quadric_decimation(target_number_of_triangles=n)
    return np.asarray(r.vertices), np.asarray(r.triangles)
def pyfqmr(n):
    import pyfqmr
    s = pyfqmr.Simplify()
    s.setMesh(v, f.astype(np.int32))
    s.simplify_mesh(target_count=n, verbose=False)
    pv, pf, _ = s.getMesh()
    return pv, pf
def fast(n):
    import fast_simplification
    pv, pf = fast_simplification.simplify(v.astype(np.float32), f.astype(np.int32), target_reduction=1.0 - n / nt)
    return pv, pf
run = {'pymeshlab': meshlab, 'open3d': open3d, 'pyfqmr': pyfqmr, 'fast_simplification': fast}
for tool in tools:
    for n in counts:
        try:
            pv, pf = run[tool](n)
            save(tool, n, pv, pf)
        except Exception as e:
            print('%s at %d: %s' % (tool, n, e), file=sys.stderr)
"#;

fn write_bin(path: &Path, m: &Mesh) -> Result<()> {
    let mut b = Vec::with_capacity(8 + 12 * (m.positions.len() + m.triangles.len()));
    b.extend_from_slice(&(m.positions.len() as u32).to_le_bytes());
    b.extend_from_slice(&(m.triangles.len() as u32).to_le_bytes());
    for p in &m.positions {
        p.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
    }
    for t in &m.triangles {
        t.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
    }
    std::fs::write(path, b).with_context(|| format!("writing {}", path.display()))
}

fn read_bin(path: &Path) -> Result<Mesh> {
    let b = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    let word = |i: usize| -> Result<[u8; 4]> {
        b.get(4 * i..4 * i + 4)
            .and_then(|s| s.try_into().ok())
            .with_context(|| format!("{} is truncated", path.display()))
    };
    let nv = u32::from_le_bytes(word(0)?) as usize;
    let nt = u32::from_le_bytes(word(1)?) as usize;
    let positions = (0..nv)
        .map(|i| {
            let f = |k| word(2 + 3 * i + k).map(f32::from_le_bytes);
            Ok([f(0)?, f(1)?, f(2)?])
        })
        .collect::<Result<Vec<_>>>()?;
    let base = 2 + 3 * nv;
    let triangles = (0..nt)
        .map(|i| {
            let u = |k| word(base + 3 * i + k).map(u32::from_le_bytes);
            Ok([u(0)?, u(1)?, u(2)?])
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Mesh {
        positions,
        triangles,
    })
}

/// The venv's python with every peer package that imports (installing
/// what is missing), or `None` with a notice.
pub(super) fn peer_python() -> Result<Option<(PathBuf, Vec<usize>)>> {
    let venv = crate::workspace_root().join("target/quality-venv");
    let py = venv.join("bin/python");
    if !py.exists() {
        eprintln!("quality: creating {}", venv.display());
        let ok = Command::new("python3")
            .args(["-m", "venv"])
            .arg(&venv)
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            eprintln!("quality: notice: python3 -m venv failed: the Python peers are skipped");
            return Ok(None);
        }
    }
    // `None` when `module` imports, else the last line of its error
    let import_error = |module: &str| -> Option<String> {
        match Command::new(&py)
            .args(["-c", &format!("import numpy, {module}")])
            .output()
        {
            Ok(o) if o.status.success() => None,
            Ok(o) => Some(
                String::from_utf8_lossy(&o.stderr)
                    .lines()
                    .last()
                    .unwrap_or("")
                    .to_string(),
            ),
            Err(e) => Some(e.to_string()),
        }
    };
    let mut usable = Vec::new();
    for (i, (label, module, package)) in PEERS.iter().enumerate() {
        if import_error(module).is_some() {
            eprintln!("quality: installing {package} (and numpy) into the venv");
            let _ = Command::new(&py)
                .args(["-m", "pip", "install", "-q", "numpy", package])
                .status();
        }
        match import_error(module) {
            None => usable.push(i),
            Some(e) => eprintln!(
                "quality: notice: {package} does not install or import here ({e}): {label} is \
                 skipped (Open3D needs the system library libusb-1.0: apt-get install \
                 libusb-1.0-0)"
            ),
        }
    }
    Ok(Some((py, usable)))
}

/// Runs the usable Python peers on `m` at each count; `None` where one
/// failed or was skipped. Indexed `[peer][count]`.
pub(super) fn python_peers(
    py: &Path,
    usable: &[usize],
    m: &Mesh,
    counts: &[usize],
) -> Result<Vec<Vec<Option<Mesh>>>> {
    let dir = tempfile::tempdir()?;
    let src = dir.path().join("in.bin");
    write_bin(&src, m)?;
    let script = dir.path().join("peers.py");
    std::fs::write(&script, PEER_SCRIPT)?;
    let modules: Vec<&str> = usable.iter().map(|&i| PEERS[i].1).collect();
    let out = dir.path().join("out");
    let status = Command::new(py)
        .arg(&script)
        .arg(&src)
        .arg(&out)
        .arg(modules.join(","))
        .args(counts.iter().map(|c| c.to_string()))
        .status()
        .context("running the Python peers")?;
    if !status.success() {
        eprintln!("quality: notice: the peer script failed ({status})");
    }
    let mut res = vec![vec![None; counts.len()]; PEERS.len()];
    for &i in usable {
        for (k, &n) in counts.iter().enumerate() {
            let f = PathBuf::from(format!("{}-{}-{n}.bin", out.display(), PEERS[i].1));
            if f.exists() {
                res[i][k] = Some(read_bin(&f)?);
            }
        }
    }
    Ok(res)
}
