//! Figures in the paper's spirit, as PNG and SVG (plotters, with an embedded DejaVu Sans so a
//! machine without fonts draws text): top-view trajectories (Fig. 1), ATE spread over runs per
//! configuration (Fig. 9), the outlier ratio over frames (Fig. 8), and a configuration's ATE
//! relative to the baseline's per sequence.

use anyhow::{anyhow, Result};
use ate_eval::Trajectory;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: Once = Once::new();

/// Registers the embedded DejaVu Sans as "sans-serif" (once per process), so a machine without
/// fonts draws every figure's text.
pub fn register_font() {
    FONT.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../../../../assets/fonts/DejaVuSans.ttf");
        // Registration fails only on a corrupt font file, which the build embeds; ignore.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, bytes);
    });
}

/// Colours of the curves, in order (ground truth first).
const PALETTE: [RGBColor; 6] = [
    RGBColor(0, 0, 0),
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
];

/// A plotters error as the figures report it.
pub fn err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("drawing a figure: {e:?}")
}

/// Encodes the RGB pixels a `BitMapBackend::with_buffer` drew (`size` = width, height) as a PNG
/// at `path` (the caller renames it into place). The figures draw into memory and encode with
/// the `image` crate the rest of noisefree uses, rather than through plotters' own encoder (a
/// second `image` version to build).
pub fn write_png(path: &Path, size: (u32, u32), pixels: Vec<u8>) -> Result<()> {
    let img = image::RgbImage::from_raw(size.0, size.1, pixels)
        .ok_or_else(|| anyhow!("a {}x{} figure buffer has the wrong size", size.0, size.1))?;
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(|e| anyhow!("writing {}: {e}", path.display()))
}

/// Draws the body into `<stem>.png` and `<stem>.svg` of `size` pixels (width, height), each
/// through a temporary file and a rename. A macro, because the body is instantiated once per
/// backend type.
macro_rules! both {
    ($stem:expr, $size:expr, |$root:ident| $body:block) => {{
        register_font();
        let stem: &Path = $stem;
        if let Some(d) = stem.parent() {
            std::fs::create_dir_all(d)?;
        }
        let tmp_png = stem.with_extension("tmp.png");
        let tmp_svg = stem.with_extension("tmp.svg");
        let (w, h): (u32, u32) = $size;
        {
            let mut pixels = vec![0u8; w as usize * h as usize * 3];
            {
                let area = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
                area.fill(&WHITE).map_err(err)?;
                (|| -> Result<()> {
                    let $root = &area;
                    $body
                })()?;
                area.present().map_err(err)?;
            }
            write_png(&tmp_png, (w, h), pixels)?;
        }
        {
            let area = SVGBackend::new(&tmp_svg, (w, h)).into_drawing_area();
            area.fill(&WHITE).map_err(err)?;
            (|| -> Result<()> {
                let $root = &area;
                $body
            })()?;
            area.present().map_err(err)?;
        }
        std::fs::rename(&tmp_png, stem.with_extension("png"))?;
        std::fs::rename(&tmp_svg, stem.with_extension("svg"))?;
        Ok(())
    }};
}

/// Where a figure's legend box sits and how large its labels are (translucent white, black
/// border, for every figure).
#[derive(Clone, Copy)]
pub struct LegendStyle {
    /// The corner of the plot: upper left when true, upper right otherwise.
    pub upper_left: bool,
    /// Label size in pixels.
    pub font_px: u32,
    /// Opacity of the white background.
    pub opacity: f64,
}

/// The results figures' legend: upper left (their axes leave room there), 18 px labels.
pub const RESULTS_LEGEND: LegendStyle = LegendStyle {
    upper_left: true,
    font_px: 18,
    opacity: 0.8,
};

/// Draws the legend of `chart`'s labelled series in `style`.
pub fn draw_legend<'a, DB: DrawingBackend + 'a, Y: Ranged<ValueType = f64>>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
    style: LegendStyle,
) -> Result<()> {
    chart
        .configure_series_labels()
        .position(if style.upper_left {
            SeriesLabelPosition::UpperLeft
        } else {
            SeriesLabelPosition::UpperRight
        })
        .background_style(WHITE.mix(style.opacity))
        .border_style(BLACK)
        .label_font(("sans-serif", style.font_px))
        .draw()
        .map_err(err)?;
    Ok(())
}

/// The two world axes spanning the plane in which the ground truth moves most (a top view for
/// a camera moving over a floor, whatever the dataset's "up" axis is).
fn top_view_axes(gt: &Trajectory) -> (usize, usize) {
    let p = gt.positions();
    let n = p.len().max(1) as f64;
    let mean = p.iter().sum::<nalgebra::Vector3<f64>>() / n;
    let var: Vec<f64> = (0..3)
        .map(|k| p.iter().map(|v| (v[k] - mean[k]).powi(2)).sum::<f64>())
        .collect();
    let smallest = (0..3)
        .min_by(|&a, &b| var[a].total_cmp(&var[b]))
        .unwrap_or(2);
    let axes: Vec<usize> = (0..3).filter(|&k| k != smallest).collect();
    (axes[0], axes[1])
}

/// Fig. 1: top view of the ground truth (black) and of aligned estimates (`curves`: name,
/// trajectory already in the ground-truth frame), curve i in `colours[i]` (a system's own,
/// [`system_colour`]) or, past them, the palette's.
pub fn trajectories(
    stem: &Path,
    title: &str,
    gt: &Trajectory,
    curves: &[(String, Trajectory)],
    colours: &[RGBColor],
) -> Result<()> {
    let (a, b) = top_view_axes(gt);
    let axis = ["x", "y", "z"];
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for t in std::iter::once(gt).chain(curves.iter().map(|c| &c.1)) {
        for p in t.positions() {
            for (k, ax) in [a, b].into_iter().enumerate() {
                lo[k] = lo[k].min(p[ax]);
                hi[k] = hi[k].max(p[ax]);
            }
        }
    }
    // Equal scale on both axes, with a margin.
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-3) * 1.1;
    let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let range = |k: usize| (c[k] - span / 2.0)..(c[k] + span / 2.0);
    both!(stem, (1000, 750), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 26))
            .margin(20)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(range(0), range(1))
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(format!("{} [m]", axis[a]))
            .y_desc(format!("{} [m]", axis[b]))
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(err)?;
        let series = std::iter::once(("ground truth".to_string(), gt))
            .chain(curves.iter().map(|(n, t)| (n.clone(), t)));
        for (i, (name, t)) in series.enumerate() {
            let color = match i.checked_sub(1).and_then(|k| colours.get(k)) {
                Some(c) => *c,
                None => PALETTE[i % PALETTE.len()],
            };
            let pts: Vec<(f64, f64)> = t.positions().iter().map(|p| (p[a], p[b])).collect();
            chart
                .draw_series(LineSeries::new(
                    pts,
                    color.stroke_width(if i == 0 { 3 } else { 2 }),
                ))
                .map_err(err)?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
                });
        }
        draw_legend(&mut chart, RESULTS_LEGEND)
    })
}

/// The colour of a system in every figure of a folder, whatever else the figure shows: the
/// paper's four columns and rc have their own, and any other column (a parameter value, a
/// reading, an external program) one of a second set chosen by its name.
pub fn system_colour(config: &str) -> RGBColor {
    match config {
        "orb" => RGBColor(214, 39, 40),
        "mcor" => RGBColor(31, 119, 180),
        "avc" => RGBColor(44, 160, 44),
        "mcor+avc" => RGBColor(255, 127, 14),
        "rc" => RGBColor(148, 103, 189),
        other => {
            const MORE: [RGBColor; 6] = [
                RGBColor(140, 86, 75),
                RGBColor(227, 119, 194),
                RGBColor(188, 189, 34),
                RGBColor(23, 190, 207),
                RGBColor(127, 127, 127),
                RGBColor(0, 0, 128),
            ];
            // FNV-1a: the same name, the same colour, on every machine.
            let h = other.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
                (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
            });
            MORE[(h % MORE.len() as u64) as usize]
        }
    }
}

/// One system's runs on one sequence, for [`ate_spread`].
#[derive(Clone, Debug)]
pub struct SpreadGroup {
    /// The sequence (an x-axis label).
    pub sequence: String,
    /// The configuration's key (its colour, [`system_colour`]).
    pub config: String,
    /// Its heading in the tables (the legend).
    pub label: String,
    /// ATE of each run, metres.
    pub ates: Vec<f64>,
    /// The paper's figure for this cell, metres (`table --paper`), drawn beside the runs.
    pub paper: Option<f64>,
}

/// Fig. 9: ATE of every run (dots) and the mean (bar) per sequence and system, in millimetres
/// on a logarithmic axis (presets span millimetres to decimetres), each system in its colour,
/// the paper's figure as a cross beside ours where it has one. Many sequences widen the figure
/// and turn their names, so 31 rows stay legible. `groups` in column order.
pub fn ate_spread(stem: &Path, title: &str, groups: &[SpreadGroup]) -> Result<()> {
    let mut seqs: Vec<String> = Vec::new();
    let mut cfgs: Vec<(String, String)> = Vec::new();
    for g in groups {
        if !seqs.contains(&g.sequence) {
            seqs.push(g.sequence.clone());
        }
        if !cfgs.iter().any(|c| c.0 == g.config) {
            cfgs.push((g.config.clone(), g.label.clone()));
        }
    }
    let mm = |a: f64| a * 1e3;
    let positive = || {
        groups
            .iter()
            .flat_map(|g| g.ates.iter().copied().chain(g.paper))
            .filter(|a| *a > 0.0 && a.is_finite())
            .map(mm)
    };
    let top = positive().fold(0.1f64, f64::max) * 1.5;
    let ymin = positive().fold(top, f64::min).min(top / 10.0) / 1.5;
    // The top of the log axis is left to the legend (upper left), so no run hides under it.
    let legend = (0.04 * (cfgs.len() + 1) as f64).clamp(0.2, 0.4);
    let ymax = ((top.ln() - legend * ymin.ln()) / (1.0 - legend)).exp();
    let ncfg = cfgs.len().max(1) as f64;
    // Room per sequence for its columns of dots; turned names under many sequences.
    let per_seq = (10.0 * ncfg).clamp(40.0, 120.0);
    let width = (220.0 + per_seq * seqs.len() as f64).clamp(1000.0, 4000.0) as u32;
    let turned = seqs.len() > 6;
    let longest = seqs.iter().map(|s| s.chars().count()).max().unwrap_or(4) as u32;
    let label_area = if turned { 25 + 9 * longest } else { 60 };
    let any_paper = groups.iter().any(|g| g.paper.is_some());
    both!(stem, (width, 700 + label_area), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 26))
            .margin(20)
            .x_label_area_size(label_area)
            .y_label_area_size(80)
            .build_cartesian_2d(-0.5f64..(seqs.len() as f64 - 0.5), (ymin..ymax).log_scale())
            .map_err(err)?;
        let seq_names = seqs.clone();
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(seqs.len().max(1))
            .x_label_formatter(&|x| {
                if turned {
                    String::new()
                } else {
                    category_label(&seq_names, *x)
                }
            })
            .y_desc("ATE RMSE [mm], log scale")
            .y_label_formatter(&|y| mm_label(*y))
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(err)?;
        if turned {
            // Turned names, each starting under its tick and running down, away from the axis
            // (plotters centres turned tick labels on the tick, over the plot).
            let style = TextStyle::from(
                ("sans-serif", 16)
                    .into_font()
                    .transform(FontTransform::Rotate90),
            );
            for (k, name) in seqs.iter().enumerate() {
                let (px, py) = chart.backend_coord(&(k as f64, ymin));
                root.draw(&Text::new(name.clone(), (px + 8, py + 8), style.clone()))
                    .map_err(err)?;
            }
        }
        for (ci, (cfg, label)) in cfgs.iter().enumerate() {
            let color = system_colour(cfg);
            let offset = (ci as f64 + 0.5) / ncfg * 0.8 - 0.4;
            let (mut dots, mut bars, mut paper) = (Vec::new(), Vec::new(), Vec::new());
            for g in groups.iter().filter(|g| &g.config == cfg) {
                let x = seqs.iter().position(|q| *q == g.sequence).unwrap_or(0) as f64 + offset;
                dots.extend(g.ates.iter().filter(|a| **a > 0.0).map(|&a| (x, mm(a))));
                if !g.ates.is_empty() {
                    let mean = g.ates.iter().sum::<f64>() / g.ates.len() as f64;
                    bars.push(((x - 0.3 / ncfg, mm(mean)), (x + 0.3 / ncfg, mm(mean))));
                }
                paper.extend(g.paper.filter(|p| *p > 0.0).map(|p| (x, mm(p))));
            }
            chart
                .draw_series(dots.iter().map(|&p| Circle::new(p, 4, color.filled())))
                .map_err(err)?
                .label(label.clone())
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, color.filled()));
            chart
                .draw_series(
                    bars.iter()
                        .map(|&(p, q)| PathElement::new(vec![p, q], color.stroke_width(3))),
                )
                .map_err(err)?;
            chart
                .draw_series(
                    paper
                        .iter()
                        .map(|&p| Cross::new(p, 7, color.stroke_width(3))),
                )
                .map_err(err)?;
        }
        if any_paper {
            // The legend's key for the crosses, drawn off the axis.
            chart
                .draw_series(std::iter::empty::<Cross<(f64, f64), i32>>())
                .map_err(err)?
                .label("the paper's figure (cross)")
                .legend(|(x, y)| Cross::new((x + 10, y), 6, BLACK.stroke_width(3)));
        }
        draw_legend(&mut chart, RESULTS_LEGEND)
    })
}

/// One sequence of [`relative_ate`]: its name, the baseline's mean ATE and every run of the
/// configuration compared with it (metres).
pub struct RelativeAte {
    /// Sequence name (the x-axis label).
    pub sequence: String,
    /// Mean ATE of the baseline's runs.
    pub baseline_mean: f64,
    /// ATE of each run of the compared configuration.
    pub runs: Vec<f64>,
}

/// A configuration's ATE against the baseline's, per sequence, on one log axis: each run's ATE
/// divided by the baseline's mean (dots), their mean (bar), and the band of +- `tolerance`
/// (e.g. 0.03) around 1. On one axis a rescue by 50x and a cost of 3 % both read.
pub fn relative_ate(
    stem: &Path,
    title: &str,
    config: &str,
    tolerance: f64,
    rows: &[RelativeAte],
) -> Result<()> {
    let ratios: Vec<Vec<f64>> = rows
        .iter()
        .map(|r| {
            r.runs
                .iter()
                .map(|a| a / r.baseline_mean)
                .filter(|q| q.is_finite() && *q > 0.0)
                .collect()
        })
        .collect();
    let all = || ratios.iter().flatten().copied();
    let ymin = all().fold(1.0 - 2.0 * tolerance, f64::min) / 1.3;
    let ymax = all().fold(1.0 + 2.0 * tolerance, f64::max) * 1.3;
    // The top of the axis is left to the legend, as in the ATE spread.
    let ymax = ymax * (ymax / ymin).powf(0.3);
    let n = rows.len();
    let names: Vec<String> = rows.iter().map(|r| r.sequence.clone()).collect();
    let color = PALETTE[5];
    both!(stem, (1000, 750), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 26))
            .margin(20)
            .x_label_area_size(60)
            .y_label_area_size(80)
            .build_cartesian_2d(-0.5f64..(n as f64 - 0.5), (ymin..ymax).log_scale())
            .map_err(err)?;
        let labels = names.clone();
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(n.max(1))
            .x_label_formatter(&|x| category_label(&labels, *x))
            .y_desc("ATE / baseline's mean ATE, log scale")
            .y_label_formatter(&|y| format!("{y:.3}"))
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(err)?;
        let band = PALETTE[3].mix(0.25);
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(-0.5, 1.0 - tolerance), (n as f64 - 0.5, 1.0 + tolerance)],
                band.filled(),
            )))
            .map_err(err)?
            .label(format!("baseline +- {:.0} %", tolerance * 100.0))
            .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 20, y + 6)], band.filled()));
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(-0.5, 1.0), (n as f64 - 0.5, 1.0)],
                BLACK.stroke_width(1),
            )))
            .map_err(err)?;
        let dots: Vec<(f64, f64)> = ratios
            .iter()
            .enumerate()
            .flat_map(|(i, q)| q.iter().map(move |&r| (i as f64, r)))
            .collect();
        chart
            .draw_series(dots.iter().map(|&p| Circle::new(p, 4, color.filled())))
            .map_err(err)?
            .label(format!("{config}, each run"))
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, color.filled()));
        let bars: Vec<PathElement<(f64, f64)>> = ratios
            .iter()
            .enumerate()
            .filter(|(_, q)| !q.is_empty())
            .map(|(i, q)| {
                let mean = q.iter().sum::<f64>() / q.len() as f64;
                let x = i as f64;
                PathElement::new(
                    vec![(x - 0.3, mean), (x + 0.3, mean)],
                    color.stroke_width(3),
                )
            })
            .collect();
        chart.draw_series(bars).map_err(err)?;
        draw_legend(&mut chart, RESULTS_LEGEND)
    })
}

/// The tick label of a categorical x axis: the name at an integer position, nothing between.
fn category_label(names: &[String], x: f64) -> String {
    let i = x.round();
    if (x - i).abs() < 1e-6 && i >= 0.0 {
        names.get(i as usize).cloned().unwrap_or_default()
    } else {
        String::new()
    }
}

/// A tick label for millimetres on a log axis: as many decimals as the value needs, and no
/// "-0.0" or "20.0" (0.5, 2, 20, 300).
fn mm_label(y: f64) -> String {
    let decimals = (-y.log10().floor()).clamp(0.0, 3.0) as usize;
    format!("{y:.decimals$}")
}

/// Fig. 8: a per-frame quantity (e.g. outlier ratio) over frames, one curve per configuration,
/// curve i in `colours[i]` or, past them, the palette's.
pub fn per_frame(
    stem: &Path,
    title: &str,
    y_desc: &str,
    series: &[(String, Vec<(f64, f64)>)],
    colours: &[RGBColor],
) -> Result<()> {
    let xmax = series
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.0))
        .fold(1.0f64, f64::max);
    let ymax = series
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.1))
        .fold(1e-3f64, f64::max)
        * 1.1;
    both!(stem, (1000, 750), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 26))
            .margin(20)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..xmax, 0.0..ymax)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("frame")
            .y_desc(y_desc)
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(err)?;
        for (i, (name, pts)) in series.iter().enumerate() {
            let color = colours
                .get(i)
                .copied()
                .unwrap_or(PALETTE[(i + 1) % PALETTE.len()]);
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                .map_err(err)?
                .label(name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
                });
        }
        draw_legend(&mut chart, RESULTS_LEGEND)
    })
}

/// One curve of [`resilience`]: its label and, per level, (level, `Some((mean, min, max))` of
/// its runs' ATE, or `None` where more than half of them failed).
pub type ResilienceCurve = (String, Vec<(f64, Option<(f64, f64, f64)>)>);

/// A resilience figure: ATE against the perturbation level, one line per system through its
/// mean, a bar over its runs' range (min to max) at each level, a cross where more than half of
/// its runs failed (drawn at the top), on a logarithmic ATE axis. Levels are spaced evenly in
/// their severity order (so 0, 1, 2, 4, 8 read as steps, and JPEG's falling quality left to
/// right). `curves`: (label, per level: (level, Some((mean, min, max)) or None for a failure)).
pub fn resilience(
    stem: &Path,
    title: &str,
    x_desc: &str,
    curves: &[ResilienceCurve],
) -> Result<()> {
    let mut levels: Vec<f64> = Vec::new();
    for (_, pts) in curves {
        for (l, _) in pts {
            if !levels.contains(l) {
                levels.push(*l);
            }
        }
    }
    let x_of = |l: f64| levels.iter().position(|k| *k == l).unwrap_or(0) as f64;
    let values = || {
        curves
            .iter()
            .flat_map(|(_, p)| p.iter().filter_map(|(_, v)| *v))
            .flat_map(|(m, a, b)| [m, a, b])
            .filter(|v| *v > 0.0 && v.is_finite())
    };
    let top = values().fold(1e-3f64, f64::max) * 2.0;
    let ymin = values().fold(top, f64::min).min(top / 10.0) / 1.5;
    const LEGEND: f64 = 0.3;
    let ymax = ((top.ln() - LEGEND * ymin.ln()) / (1.0 - LEGEND)).exp();
    let names: Vec<String> = levels.iter().map(|l| format!("{l}")).collect();
    both!(stem, (1000, 750), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 26))
            .margin(20)
            .x_label_area_size(60)
            .y_label_area_size(80)
            .build_cartesian_2d(
                -0.3f64..(levels.len() as f64 - 0.7),
                (ymin..ymax).log_scale(),
            )
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(levels.len().max(1))
            .x_label_formatter(&|x| category_label(&names, *x))
            .x_desc(x_desc)
            .y_labels(20)
            .y_desc("ATE RMSE [mm], log scale")
            .y_label_formatter(&|y| {
                let mm = *y * 1000.0;
                let d = (1.0 - mm.log10().floor()).clamp(0.0, 3.0) as usize;
                format!("{mm:.d$}")
            })
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(err)?;
        let n = curves.len().max(1) as f64;
        for (ci, (label, pts)) in curves.iter().enumerate() {
            let color = PALETTE[(ci + 1) % PALETTE.len()];
            // A small offset per system, so bars at one level do not hide each other.
            let dx = (ci as f64 + 0.5) / n * 0.3 - 0.15;
            let line: Vec<(f64, f64)> = pts
                .iter()
                .filter_map(|(l, v)| v.map(|(m, _, _)| (x_of(*l) + dx, m)))
                .collect();
            chart
                .draw_series(LineSeries::new(line.clone(), color.stroke_width(3)))
                .map_err(err)?
                .label(label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
                });
            chart
                .draw_series(line.iter().map(|&p| Circle::new(p, 5, color.filled())))
                .map_err(err)?;
            chart
                .draw_series(pts.iter().filter_map(|(l, v)| {
                    v.map(|(_, a, b)| {
                        let x = x_of(*l) + dx;
                        PathElement::new(
                            vec![(x, a.max(ymin)), (x, b.max(ymin))],
                            color.stroke_width(2),
                        )
                    })
                }))
                .map_err(err)?;
            chart
                .draw_series(
                    pts.iter().filter(|(_, v)| v.is_none()).map(|(l, _)| {
                        Cross::new((x_of(*l) + dx, top / 1.3), 8, color.stroke_width(3))
                    }),
                )
                .map_err(err)?;
        }
        draw_legend(&mut chart, RESULTS_LEGEND)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Table III's 31 rows and 9 columns: the figure widens so each row keeps room for its
    /// columns and its name, and every system keeps its colour.
    #[test]
    fn a_31_row_spread_widens_and_each_system_keeps_its_colour() {
        let configs = [
            "orb", "mcor", "avc", "mcor+avc", "rc", "orbslam2", "orbslam3", "x", "y",
        ];
        let groups: Vec<SpreadGroup> = (0..31)
            .flat_map(|s| {
                configs.iter().map(move |c| SpreadGroup {
                    sequence: format!("twin_sequence_{s:02}"),
                    config: c.to_string(),
                    label: c.to_string(),
                    ates: vec![0.01 * (1 + s) as f64, 0.012 * (1 + s) as f64],
                    paper: (*c == "orb").then_some(0.02),
                })
            })
            .collect();
        let dir = std::env::temp_dir().join(format!("nf-spread-{}", std::process::id()));
        let stem = dir.join("ate_spread");
        ate_spread(&stem, "31 rows", &groups).unwrap();
        let img = image::open(stem.with_extension("png")).unwrap().to_rgb8();
        assert!(img.width() >= 31 * 80, "{} px wide", img.width());
        assert!(img.height() > 750, "room under the axis for turned names");
        let red = system_colour("orb");
        let has = |c: RGBColor| img.pixels().any(|p| p.0 == [c.0, c.1, c.2]);
        assert!(has(red) && has(system_colour("mcor")) && has(system_colour("avc")));
        assert_eq!(
            system_colour("orb"),
            RGBColor(214, 39, 40),
            "the baseline is red everywhere"
        );
        assert_eq!(system_colour("mcor:paper"), system_colour("mcor:paper"));
        assert_eq!(mm_label(20.0), "20");
        assert_eq!(mm_label(0.5), "0.5");
        let _ = std::fs::remove_dir_all(dir);
    }
}
