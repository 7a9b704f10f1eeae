//! docs/quality.png: error against triangle count, one panel per mesh,
//! Hausdorff above, RMS below (lodgen and every peer, log-log).

use super::{peer_labels, Cell, Row, DEFAULT_FONT, PLOT_PANEL};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

pub(super) fn plot(path: &Path, meshes: &[&str], rows: &[Row]) -> Result<()> {
    use plotters::prelude::*;
    let font_path = std::env::var_os("LODGEN_FONT")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(DEFAULT_FONT));
    let font = std::fs::read(&font_path)
        .with_context(|| format!("reading the plot font {}", font_path.display()))?;
    let font: &'static [u8] = Box::leak(font.into_boxed_slice());
    plotters::style::register_font("sans-serif", FontStyle::Normal, font)
        .map_err(|_| anyhow::anyhow!("{} is not a usable font", font_path.display()))?;
    let cols = meshes.len().max(1) as u32;
    let (w, h) = (PLOT_PANEL.0 * cols, PLOT_PANEL.1 * 2);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    let mut labels = vec!["lodgen"];
    labels.extend(peer_labels());
    let colours = [
        RGBColor(214, 39, 40),
        RGBColor(60, 60, 60),
        RGBColor(31, 119, 180),
        RGBColor(44, 160, 44),
        RGBColor(255, 127, 14),
        RGBColor(148, 103, 189),
    ];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e}"))?;
        let panels = root.split_evenly((2, cols as usize));
        for (r, metric) in ["Hausdorff", "RMS"].iter().enumerate() {
            for (col, m) in meshes.iter().enumerate() {
                let of = |c: &Cell| {
                    let e = if r == 0 { c.hausdorff } else { c.rms };
                    e.max(1e-5)
                };
                // (tool, triangles, error)
                let mut pts: Vec<(usize, f64, f64)> = Vec::new();
                for row in rows.iter().filter(|x| x.mesh == *m) {
                    pts.push((0, row.lodgen.triangles as f64, of(&row.lodgen)));
                    for (i, c) in row.peers.iter().enumerate() {
                        if let Some(c) = c {
                            pts.push((i + 1, c.triangles.max(1) as f64, of(c)));
                        }
                    }
                }
                if pts.is_empty() {
                    continue;
                }
                let xs = pts.iter().map(|p| p.1);
                let (x0, x1) = (
                    xs.clone().fold(f64::INFINITY, f64::min),
                    xs.fold(1.0, f64::max),
                );
                let ys = pts.iter().map(|p| p.2);
                let (y0, y1) = (
                    ys.clone().fold(f64::INFINITY, f64::min),
                    ys.fold(0.0, f64::max),
                );
                let mut chart = ChartBuilder::on(&panels[r * cols as usize + col])
                    .caption(format!("{m}: {metric} %"), ("sans-serif", 16))
                    .margin(8)
                    .x_label_area_size(30)
                    .y_label_area_size(50)
                    .build_cartesian_2d(
                        (x0 * 0.8..x1 * 1.25).log_scale(),
                        (y0 * 0.7..y1 * 1.4).log_scale(),
                    )
                    .map_err(|e| anyhow::anyhow!("{e}"))?;
                chart
                    .configure_mesh()
                    .x_desc("triangles")
                    .x_labels(4)
                    .y_labels(5)
                    .label_style(("sans-serif", 11))
                    .draw()
                    .map_err(|e| anyhow::anyhow!("{e}"))?;
                for (t, label) in labels.iter().enumerate() {
                    let mut series: Vec<(f64, f64)> = pts
                        .iter()
                        .filter(|p| p.0 == t)
                        .map(|p| (p.1, p.2))
                        .collect();
                    if series.is_empty() {
                        continue;
                    }
                    series.sort_by(|a, b| a.0.total_cmp(&b.0));
                    let c = colours[t % colours.len()];
                    let width = if t == 0 { 3 } else { 1 };
                    let drawn = chart
                        .draw_series(LineSeries::new(series.clone(), c.stroke_width(width)))
                        .map_err(|e| anyhow::anyhow!("{e}"))?;
                    if r == 0 && col == 0 {
                        drawn.label(*label).legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(3))
                        });
                    }
                    chart
                        .draw_series(series.iter().map(|&p| Circle::new(p, 3, c.filled())))
                        .map_err(|e| anyhow::anyhow!("{e}"))?;
                }
                if r == 0 && col == 0 {
                    chart
                        .configure_series_labels()
                        .background_style(WHITE.mix(0.85))
                        .border_style(BLACK)
                        .label_font(("sans-serif", 11))
                        .position(SeriesLabelPosition::LowerLeft)
                        .draw()
                        .map_err(|e| anyhow::anyhow!("{e}"))?;
                }
            }
        }
        root.present().map_err(|e| anyhow::anyhow!("{e}"))?;
    }
    crate::render::write_png(path, w as usize, h as usize, &buf)
}
