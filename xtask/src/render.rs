//! A small software rasterizer for the comparison's pictures: orthographic
//! camera, z-buffer, flat shading (one colour per triangle from its normal),
//! 3× supersampling, PNG output. Back faces (seen through holes) are tinted
//! red so a flipped or missing patch is visible.

use anyhow::{Context, Result};
use std::path::Path;

/// Supersampling factor per axis: 3×3 samples per output pixel keep silhouette
/// edges from stair-stepping at 256 px without a real anti-aliasing pass.
const SUPERSAMPLE: usize = 3;

/// Light direction in view space (towards the viewer, up and to the left).
const LIGHT: [f64; 3] = [-0.35, 0.5, 0.79];

/// Ambient term: faces turned away from the light stay readable.
const AMBIENT: f64 = 0.18;

const BACKGROUND: [u8; 3] = [255, 255, 255];
const FRONT: [f64; 3] = [0.80, 0.82, 0.88];
const BACK: [f64; 3] = [0.85, 0.35, 0.30];

/// Where the camera looks from: a rotation (yaw about y, then pitch about x)
/// and the box that is framed. The same `View` for every method gives
/// pictures that line up.
#[derive(Clone, Copy, Debug)]
pub struct View {
    rot: [[f64; 3]; 3],
    center: [f64; 3],
    /// World units per output pixel.
    scale: f64,
    size: usize,
}

fn mul(m: &[[f64; 3]; 3], p: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2])
}

impl View {
    /// Frame `positions` (the original mesh) in a `size`² image, seen from
    /// `yaw` degrees around the vertical axis and `pitch` degrees above.
    pub fn fit(positions: &[[f32; 3]], yaw: f64, pitch: f64, size: usize) -> View {
        let (sy, cy) = yaw.to_radians().sin_cos();
        let (sp, cp) = pitch.to_radians().sin_cos();
        let ry = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]];
        let rx = [[1.0, 0.0, 0.0], [0.0, cp, -sp], [0.0, sp, cp]];
        let mut rot = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                rot[i][j] = (0..3).map(|k| rx[i][k] * ry[k][j]).sum();
            }
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in positions {
            let q = mul(&rot, p.map(f64::from));
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-12);
        View {
            rot,
            center: [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k])),
            // a 6 % margin on each side
            scale: extent * 1.12 / size as f64,
            size,
        }
    }
}

/// Render a mesh; returns `size × size` RGB8 pixels, rows top to bottom.
pub fn render(positions: &[[f32; 3]], triangles: &[[u32; 3]], view: &View) -> Vec<u8> {
    let n = view.size * SUPERSAMPLE;
    let px = view.scale / SUPERSAMPLE as f64;
    let screen: Vec<[f64; 3]> = positions
        .iter()
        .map(|p| {
            let q = mul(&view.rot, p.map(f64::from));
            [
                (q[0] - view.center[0]) / px + n as f64 / 2.0,
                n as f64 / 2.0 - (q[1] - view.center[1]) / px,
                // same units as x and y, so the normal below is true
                (q[2] - view.center[2]) / px,
            ]
        })
        .collect();
    let l = {
        let len = LIGHT.iter().map(|x| x * x).sum::<f64>().sqrt();
        LIGHT.map(|x| x / len)
    };
    let mut depth = vec![f64::NEG_INFINITY; n * n];
    let mut color = vec![BACKGROUND.map(f64::from); n * n];
    for t in triangles {
        let [a, b, c] = t.map(|v| screen[v as usize]);
        // view-space normal (z towards the viewer); screen y points down
        let e1 = [b[0] - a[0], -(b[1] - a[1]), b[2] - a[2]];
        let e2 = [c[0] - a[0], -(c[1] - a[1]), c[2] - a[2]];
        let nrm = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let len = nrm.iter().map(|x| x * x).sum::<f64>().sqrt();
        if len == 0.0 {
            continue;
        }
        let front = nrm[2] >= 0.0;
        let s = if front { 1.0 } else { -1.0 };
        let lambert = (s * (nrm[0] * l[0] + nrm[1] * l[1] + nrm[2] * l[2]) / len).max(0.0);
        let base = if front { FRONT } else { BACK };
        let shade = base.map(|x| 255.0 * x * (AMBIENT + (1.0 - AMBIENT) * lambert));
        // edge functions over the bounding box, sampled at pixel centres
        let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if area == 0.0 {
            continue;
        }
        let x0 = a[0].min(b[0]).min(c[0]).floor().max(0.0) as usize;
        let x1 = (a[0].max(b[0]).max(c[0]).ceil() as usize).min(n);
        let y0 = a[1].min(b[1]).min(c[1]).floor().max(0.0) as usize;
        let y1 = (a[1].max(b[1]).max(c[1]).ceil() as usize).min(n);
        for y in y0..y1 {
            let py = y as f64 + 0.5;
            for x in x0..x1 {
                let pxx = x as f64 + 0.5;
                let w0 = ((b[0] - pxx) * (c[1] - py) - (b[1] - py) * (c[0] - pxx)) / area;
                let w1 = ((c[0] - pxx) * (a[1] - py) - (c[1] - py) * (a[0] - pxx)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = w0 * a[2] + w1 * b[2] + w2 * c[2];
                let i = y * n + x;
                if z > depth[i] {
                    depth[i] = z;
                    color[i] = shade;
                }
            }
        }
    }
    // box-filter down to the output size
    let out_n = view.size;
    let mut out = vec![0u8; out_n * out_n * 3];
    let k = (SUPERSAMPLE * SUPERSAMPLE) as f64;
    for y in 0..out_n {
        for x in 0..out_n {
            let mut acc = [0.0; 3];
            for dy in 0..SUPERSAMPLE {
                for dx in 0..SUPERSAMPLE {
                    let c = color[(y * SUPERSAMPLE + dy) * n + x * SUPERSAMPLE + dx];
                    for ch in 0..3 {
                        acc[ch] += c[ch];
                    }
                }
            }
            for ch in 0..3 {
                out[(y * out_n + x) * 3 + ch] = (acc[ch] / k).round().clamp(0.0, 255.0) as u8;
            }
        }
    }
    out
}

/// Write RGB8 pixels as a PNG.
pub fn write_png(path: &Path, width: usize, height: usize, rgb: &[u8]) -> Result<()> {
    let file =
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width as u32, height as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc
        .write_header()
        .with_context(|| format!("writing {}", path.display()))?;
    w.write_image_data(rgb)
        .with_context(|| format!("writing {}", path.display()))?;
    w.finish()
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
