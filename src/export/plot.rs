//! PNG plots (plotters, bitmap backend) for reports and training logs: histograms
//! and line plots. Text uses the DejaVu Sans font embedded in the library
//! (assets/fonts, Bitstream Vera licence), so plots render the same on a machine
//! without any font installed.

use crate::diffusion::train::read_loss_csv;
use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: Once = Once::new();
const FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

fn ensure_font() {
    FONT.call_once(|| {
        // the embedded font is valid (checked by the tests); an error here would only
        // mean that text is not drawn
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT_BYTES);
    });
}

fn plot_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::io(path.display(), format!("cannot draw the plot: {e}"))
}

/// Pixel size of every plot.
pub const WIDTH: u32 = 900;
pub const HEIGHT: u32 = 520;

/// A histogram of `counts` over equal bins of [lo, hi] as a PNG, counts on a
/// logarithmic axis (a few bad elements among thousands stay visible; an empty bin
/// draws nothing), with an optional vertical line at a goal `(x, label)`.
pub fn histogram_png(path: &Path, counts: &[usize], lo: f64, hi: f64, title: &str, xlabel: &str, goal: Option<(f64, &str)>) -> Result<()> {
    ensure_font();
    if counts.is_empty() || !(hi > lo) {
        return Err(Error::InvalidArgument(format!("histogram needs bins and lo < hi (got {} bins, [{lo}, {hi}])", counts.len())));
    }
    let root = BitMapBackend::new(path, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    // bars start below 1 so that a bin with one element shows
    const BASE: f64 = 0.5;
    let ymax = counts.iter().copied().max().unwrap_or(1).max(1) as f64 * 2.0;
    let w = (hi - lo) / counts.len() as f64;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 24))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(lo..hi, (BASE..ymax).log_scale())
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc(xlabel)
        .y_desc("count (log scale)")
        .y_label_formatter(&|v| if *v < 1.0 { String::new() } else { format!("{v:.0}") })
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 17))
        .draw()
        .map_err(|e| plot_err(path, e))?;
    chart
        .draw_series(counts.iter().enumerate().filter(|(_, &c)| c > 0).map(|(i, &c)| {
            let x0 = lo + i as f64 * w;
            let colour = if x0 + w <= 0.0 { RGBColor(200, 60, 50) } else { RGBColor(60, 110, 180) };
            Rectangle::new([(x0 + 0.05 * w, BASE), (x0 + 0.95 * w, c as f64)], colour.filled())
        }))
        .map_err(|e| plot_err(path, e))?;
    if let Some((x, label)) = goal.filter(|(x, _)| x.is_finite() && (lo..=hi).contains(x)) {
        let red = RGBColor(200, 40, 40);
        chart.draw_series(LineSeries::new([(x, BASE), (x, ymax)], red.stroke_width(2))).map_err(|e| plot_err(path, e))?;
        chart
            .draw_series(std::iter::once(Text::new(label.to_string(), (x + 0.012 * (hi - lo), ymax / 1.6), ("sans-serif", 15).into_font().color(&red))))
            .map_err(|e| plot_err(path, e))?;
    }
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(())
}

/// A tick value that is zero up to rounding (the axis span times 1e-9) is zero, so a
/// tick at 0 does not read -5.55e-17.
fn snap(v: f64, span: f64) -> f64 {
    if v.abs() <= 1e-9 * span.abs() {
        0.0
    } else {
        v
    }
}

/// Axis label: at most 3 significant digits, scientific notation for small or large values.
fn short(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.2e}")
    } else {
        let digits = (2 - a.log10().floor() as i32).clamp(0, 6) as usize;
        let s = format!("{v:.digits$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    }
}

/// One named line of a [`line_png`] plot.
pub struct Series<'a> {
    pub name: &'a str,
    pub points: Vec<(f64, f64)>,
}

/// Line plot of several series as a PNG; `log_y` uses a logarithmic y axis (points
/// with y <= 0 are then skipped).
pub fn line_png(path: &Path, series: &[Series], title: &str, xlabel: &str, ylabel: &str, log_y: bool) -> Result<()> {
    ensure_font();
    let pts = || series.iter().flat_map(|s| s.points.iter()).filter(|p| p.0.is_finite() && p.1.is_finite() && (!log_y || p.1 > 0.0));
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for p in pts() {
        x0 = x0.min(p.0);
        x1 = x1.max(p.0);
        y0 = y0.min(p.1);
        y1 = y1.max(p.1);
    }
    if !x0.is_finite() {
        return Err(Error::InvalidArgument(format!("{}: nothing to plot", path.display())));
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if y1 <= y0 {
        y1 = y0 + y0.abs().max(1e-12);
    }
    let root = BitMapBackend::new(path, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let palette = [
        RGBColor(60, 110, 180),
        RGBColor(220, 110, 40),
        RGBColor(60, 160, 80),
        RGBColor(170, 60, 160),
        RGBColor(120, 120, 120),
        RGBColor(200, 50, 50),
        RGBColor(40, 170, 170),
        RGBColor(150, 120, 30),
    ];
    // the legend goes to the corner whose quarter of the plot holds the fewest points
    let legend_at = {
        let (ym0, ym1) = if log_y { (y0.ln(), (y1 * 1.05).ln()) } else { (y0, y1) };
        let yv = |y: f64| if log_y { y.ln() } else { y };
        let mut best = (usize::MAX, SeriesLabelPosition::UpperRight);
        for (pos, right, upper) in [
            (SeriesLabelPosition::UpperRight, true, true),
            (SeriesLabelPosition::UpperLeft, false, true),
            (SeriesLabelPosition::LowerRight, true, false),
            (SeriesLabelPosition::LowerLeft, false, false),
        ] {
            let n = pts()
                .filter(|p| {
                    let fx = (p.0 - x0) / (x1 - x0);
                    let fy = (yv(p.1) - ym0) / (ym1 - ym0);
                    (if right { fx > 0.6 } else { fx < 0.4 }) && (if upper { fy > 0.55 } else { fy < 0.45 })
                })
                .count();
            if n < best.0 {
                best = (n, pos);
            }
        }
        best.1
    };
    macro_rules! draw {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(xlabel)
                .y_desc(ylabel)
                .y_label_formatter(&|v: &f64| short(snap(*v, y1 - y0)))
                .x_label_formatter(&|v: &f64| short(snap(*v, x1 - x0)))
                .label_style(("sans-serif", 15))
                .axis_desc_style(("sans-serif", 17))
                .draw()
                .map_err(|e| plot_err(path, e))?;
            for (i, s) in series.iter().enumerate() {
                let c = palette[i % palette.len()];
                let p: Vec<(f64, f64)> = s.points.iter().copied().filter(|p| p.0.is_finite() && p.1.is_finite() && (!log_y || p.1 > 0.0)).collect();
                chart
                    .draw_series(LineSeries::new(p, c.stroke_width(2)))
                    .map_err(|e| plot_err(path, e))?
                    .label(s.name)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
            }
            if series.len() > 1 {
                chart
                    .configure_series_labels()
                    .position(legend_at.clone())
                    .label_font(("sans-serif", 15))
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .draw()
                    .map_err(|e| plot_err(path, e))?;
            }
        }};
    }
    let mut b = ChartBuilder::on(&root);
    b.caption(title, ("sans-serif", 24)).margin(14).x_label_area_size(44).y_label_area_size(74);
    if log_y {
        draw!(b.build_cartesian_2d(x0..x1, (y0..y1 * 1.05).log_scale()).map_err(|e| plot_err(path, e))?);
    } else {
        let pad = 0.05 * (y1 - y0);
        draw!(b.build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad)).map_err(|e| plot_err(path, e))?);
    }
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(())
}

/// Horizontal bar chart (one bar per label), e.g. stage timings.
pub fn bars_png(path: &Path, bars: &[(String, f64)], title: &str, xlabel: &str) -> Result<()> {
    ensure_font();
    if bars.is_empty() {
        return Err(Error::InvalidArgument(format!("{}: nothing to plot", path.display())));
    }
    let xmax = bars.iter().map(|b| b.1).fold(0.0f64, f64::max).max(1e-9) * 1.1;
    let n = bars.len();
    let root = BitMapBackend::new(path, (WIDTH, (120 + 34 * n as u32).max(220))).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    // one bar per stage centred on its row (row n - 1 - i for bar i: the first on
    // top), with a gap between bars; the label is the tick at the row's centre
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 24))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(150)
        .build_cartesian_2d(0.0..xmax, -0.5..n as f64 - 0.5)
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc(xlabel)
        .y_labels(n)
        .y_label_formatter(&|v| {
            let r = v.round();
            if (v - r).abs() < 1e-6 && r >= 0.0 && (r as usize) < n {
                bars[n - 1 - r as usize].0.clone()
            } else {
                String::new()
            }
        })
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 17))
        .disable_y_mesh()
        .draw()
        .map_err(|e| plot_err(path, e))?;
    chart
        .draw_series(bars.iter().enumerate().map(|(i, (_, v))| {
            let r = (n - 1 - i) as f64;
            Rectangle::new([(0.0, r - 0.35), (*v, r + 0.35)], RGBColor(60, 110, 180).filled())
        }))
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(())
}

/// Plot a training loss log (`loss.csv` of a checkpoint folder,
/// [`crate::diffusion::train::read_loss_csv`]) as three PNGs in `dir`:
/// loss.png (whole run, log scale, raw and a moving average over `window` log
/// entries), loss_tail.png (the last 20 % of the steps, linear scale) and
/// loss_gradient.png (d loss / d epoch of the moving average). Returns the file names.
pub fn plot_loss(csv: &Path, dir: &Path, window: usize) -> Result<Vec<String>> {
    let rows = read_loss_csv(csv)?;
    if rows.len() < 2 {
        return Err(Error::InvalidArgument(format!("{}: fewer than two loss entries", csv.display())));
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir.display(), e))?;
    let w = window.max(1);
    let raw: Vec<(f64, f64)> = rows.iter().map(|r| (r.1, r.2)).collect();
    let smooth: Vec<(f64, f64)> = (0..rows.len())
        .map(|i| {
            let lo = i.saturating_sub(w / 2);
            let hi = (i + w / 2 + 1).min(rows.len());
            (rows[i].1, rows[lo..hi].iter().map(|r| r.2).sum::<f64>() / (hi - lo) as f64)
        })
        .collect();
    let mut names = Vec::new();
    let p = dir.join("loss.png");
    line_png(&p, &[Series { name: "loss (logged every 25 steps)", points: raw.clone() }, Series { name: "moving average", points: smooth.clone() }], "Training loss (MSE on the noise)", "epoch", "loss", true)?;
    names.push("loss.png".to_string());
    let cut = rows.len() * 4 / 5;
    let p = dir.join("loss_tail.png");
    line_png(&p, &[Series { name: "loss", points: raw[cut..].to_vec() }, Series { name: "moving average", points: smooth[cut..].to_vec() }], "Training loss, last 20 % of the steps", "epoch", "loss", false)?;
    names.push("loss_tail.png".to_string());
    let grad: Vec<(f64, f64)> = smooth
        .windows(2)
        .filter(|s| s[1].0 > s[0].0)
        .map(|s| (0.5 * (s[0].0 + s[1].0), (s[1].1 - s[0].1) / (s[1].0 - s[0].0)))
        .collect();
    if grad.len() >= 2 {
        let p = dir.join("loss_gradient.png");
        line_png(&p, &[Series { name: "d loss / d epoch (moving average)", points: grad }], "Gradient of the training loss", "epoch", "d loss / d epoch", false)?;
        names.push("loss_gradient.png".to_string());
    }
    Ok(names)
}
