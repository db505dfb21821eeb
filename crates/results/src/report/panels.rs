//! Drawings of the analyses: the paper's Fig. 8 (per-frame inlier and outlier counts with and
//! without MC-OR, two stacked panels, PNG + SVG through plotters with the embedded DejaVu Sans)
//! and Fig. 7 (one frame in grey with the features MC-OR kept in green and rejected in red,
//! a PNG through the image crate).

use crate::report::figures::{draw_legend, err, register_font, LegendStyle};
use anyhow::{Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use slam_core::GrayImage;
use std::path::Path;

/// The per-frame panels' legend: upper right (the curves start low at the left), 15 px labels
/// to match the panels' axis labels.
const PANEL_LEGEND: LegendStyle = LegendStyle {
    upper_left: false,
    font_px: 15,
    opacity: 0.85,
};

/// Blue: the baseline (ORB-SLAM2).
pub const BASELINE_COLOR: RGBColor = RGBColor(31, 119, 180);
/// Red: with MC-OR.
pub const MCOR_COLOR: RGBColor = RGBColor(214, 39, 40);
/// Green: matches on moving objects.
pub const MOVING_COLOR: RGBColor = RGBColor(44, 160, 44);
/// Orange: MC-OR's rejections (part of its outliers).
pub const REJECTED_COLOR: RGBColor = RGBColor(255, 127, 14);

/// One curve of a panel: legend label, colour, y per frame (x = frame index), dashed or not.
pub struct Curve {
    /// Legend label.
    pub label: String,
    /// Line colour.
    pub color: RGBColor,
    /// One value per frame (not finite: no value at that frame).
    pub values: Vec<f64>,
    /// Thin dashed-looking line (drawn as points) instead of a solid one.
    pub thin: bool,
}

/// One panel: y-axis description and curves.
pub struct Panel {
    /// y-axis description.
    pub y_desc: String,
    /// Curves.
    pub curves: Vec<Curve>,
}

fn draw_panels<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    panels: &[Panel],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let root = root.titled(title, ("sans-serif", 26)).map_err(err)?;
    let areas = root.split_evenly((panels.len(), 1));
    for (area, panel) in areas.iter().zip(panels) {
        let xmax = panel
            .curves
            .iter()
            .map(|c| c.values.len())
            .max()
            .unwrap_or(1)
            .max(2) as f64
            - 1.0;
        let ymax = panel
            .curves
            .iter()
            .flat_map(|c| c.values.iter().copied())
            .fold(1.0f64, f64::max)
            * 1.15;
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..xmax, 0.0..ymax)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("frame")
            .y_desc(panel.y_desc.as_str())
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&|y| format!("{y:.0}"))
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 17))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(err)?;
        for c in &panel.curves {
            let pts: Vec<(f64, f64)> = c
                .values
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_finite())
                .map(|(i, v)| (i as f64, *v))
                .collect();
            let color = c.color;
            let width = if c.thin { 1 } else { 2 };
            chart
                .draw_series(LineSeries::new(pts, color.stroke_width(width)))
                .map_err(err)?
                .label(c.label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(3))
                });
        }
        draw_legend(&mut chart, PANEL_LEGEND)?;
    }
    Ok(())
}

/// Fig. 8: stacked per-frame panels into `<stem>.png` (1000 wide, 300 high per panel) and `<stem>.svg`, each
/// through a temporary file and a rename.
pub fn per_frame_panels(stem: &Path, title: &str, panels: &[Panel]) -> Result<()> {
    register_font();
    if let Some(d) = stem.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(d).with_context(|| format!("creating {}", d.display()))?;
    }
    let size = (1000, 300 * panels.len().max(1) as u32);
    let tmp_png = stem.with_extension("tmp.png");
    let tmp_svg = stem.with_extension("tmp.svg");
    {
        let mut pixels = vec![0u8; size.0 as usize * size.1 as usize * 3];
        {
            let area = BitMapBackend::with_buffer(&mut pixels, size).into_drawing_area();
            draw_panels(&area, title, panels)?;
            area.present().map_err(err)?;
        }
        crate::report::figures::write_png(&tmp_png, size, pixels)?;
    }
    {
        let area = SVGBackend::new(&tmp_svg, size).into_drawing_area();
        draw_panels(&area, title, panels)?;
        area.present().map_err(err)?;
    }
    for (tmp, ext) in [(&tmp_png, "png"), (&tmp_svg, "svg")] {
        let dst = stem.with_extension(ext);
        std::fs::rename(tmp, &dst).with_context(|| format!("writing {}", dst.display()))?;
    }
    Ok(())
}

/// What MC-OR decided for one drawn feature.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// Kept (enters the optimization): green circle.
    Kept,
    /// Rejected by the feature-level test: red circle with a cross.
    RejectedFeature,
    /// Rejected with its whole cluster (map point): red square.
    RejectedCluster,
}

/// One feature to draw at raw pixel (x, y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarkedFeature {
    /// Raw pixel column.
    pub x: f64,
    /// Raw pixel row.
    pub y: f64,
    /// The verdict.
    pub mark: Mark,
}

/// Upscaling of the Fig. 7 picture (nearest neighbour) so the markers stay legible.
pub const FIG7_SCALE: u32 = 2;
/// Height of the legend strip under the Fig. 7 picture, pixels.
const LEGEND_HEIGHT: u32 = 70;

/// Fig. 7: `image` in (dimmed) grey, pixels of moving objects tinted blue when `moving` is
/// given, kept features green, MC-OR-rejected ones red, a legend with `caption` underneath;
/// PNG at `path` (through a temporary file and a rename).
pub fn rejected_features_image(
    path: &Path,
    image: &GrayImage,
    moving: Option<&[bool]>,
    features: &[MarkedFeature],
    caption: &str,
) -> Result<()> {
    register_font();
    let s = FIG7_SCALE;
    let (w, h) = (image.width as u32 * s, image.height as u32 * s);
    let total_h = h + LEGEND_HEIGHT;
    let mut buf = vec![255u8; (w * total_h * 3) as usize];
    for y in 0..h {
        for x in 0..w {
            let (sx, sy) = ((x / s) as usize, (y / s) as usize);
            let g = image.data[sy * image.width + sx] as f64;
            // Dimmed and lifted so that coloured markers stand out on any texture.
            let g = 60.0 + 0.6 * g;
            let on_moving = moving.is_some_and(|m| m[sy * image.width + sx]);
            let rgb = if on_moving {
                [0.7 * g, 0.8 * g, (g + 70.0).min(255.0)]
            } else {
                [g, g, g]
            };
            let o = ((y * w + x) * 3) as usize;
            for k in 0..3 {
                buf[o + k] = rgb[k].round() as u8;
            }
        }
    }
    {
        let area = BitMapBackend::with_buffer(&mut buf, (w, total_h)).into_drawing_area();
        let green = RGBColor(0, 200, 60);
        let red = RGBColor(235, 20, 20);
        let r = 4 * s as i32;
        let at = |f: &MarkedFeature| ((f.x * s as f64) as i32, (f.y * s as f64) as i32);
        // Kept first, so rejections are drawn on top.
        for f in features.iter().filter(|f| f.mark == Mark::Kept) {
            area.draw(&Circle::new(at(f), r, green.stroke_width(2)))
                .map_err(err)?;
        }
        for f in features.iter().filter(|f| f.mark != Mark::Kept) {
            let (x, y) = at(f);
            match f.mark {
                Mark::RejectedCluster => area
                    .draw(&Rectangle::new(
                        [(x - r, y - r), (x + r, y + r)],
                        red.stroke_width(3),
                    ))
                    .map_err(err)?,
                _ => {
                    area.draw(&Circle::new((x, y), r + 1, red.stroke_width(3)))
                        .map_err(err)?;
                    area.draw(&PathElement::new(
                        vec![(x - r, y - r), (x + r, y + r)],
                        red.stroke_width(2),
                    ))
                    .map_err(err)?;
                }
            }
        }
        let y0 = h as i32;
        let font = ("sans-serif", 20).into_font().color(&BLACK);
        let small = ("sans-serif", 17).into_font().color(&BLACK);
        area.draw(&Circle::new((20, y0 + 22), r, green.stroke_width(2)))
            .map_err(err)?;
        area.draw(&Text::new("kept by MC-OR", (34, y0 + 12), font.clone()))
            .map_err(err)?;
        area.draw(&Circle::new((220, y0 + 22), r + 1, red.stroke_width(3)))
            .map_err(err)?;
        area.draw(&Text::new(
            "rejected feature (FL test)",
            (236, y0 + 12),
            font.clone(),
        ))
        .map_err(err)?;
        area.draw(&Rectangle::new(
            [(512 - r, y0 + 22 - r), (512 + r, y0 + 22 + r)],
            red.stroke_width(3),
        ))
        .map_err(err)?;
        area.draw(&Text::new(
            "rejected map point (CL test)",
            (528, y0 + 12),
            font.clone(),
        ))
        .map_err(err)?;
        if moving.is_some() {
            area.draw(&Rectangle::new(
                [(850, y0 + 14), (866, y0 + 30)],
                RGBColor(110, 125, 220).filled(),
            ))
            .map_err(err)?;
            area.draw(&Text::new("moving object", (874, y0 + 12), font))
                .map_err(err)?;
        }
        area.draw(&Text::new(caption.to_string(), (12, y0 + 42), small))
            .map_err(err)?;
        area.present().map_err(err)?;
    }
    let tmp = path.with_extension("tmp.png");
    crate::report::figures::write_png(&tmp, (w, total_h), buf)?;
    std::fs::rename(&tmp, path).with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
