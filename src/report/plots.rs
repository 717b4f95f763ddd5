//! PNG plots with plotters: time series with a marked window, spectra with marked peaks, and
//! colour maps of 2D fields.

use std::ops::Range;
use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::FontStyle;

static FONT: Once = Once::new();
static FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// Registers the embedded font as "sans-serif" (once per process).
fn fonts() {
    FONT.call_once(|| {
        // The font is a valid TrueType file compiled into the binary; a failure would only mean
        // text is missing from plots, never a crash.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT_BYTES);
    });
}

/// A plot that could not be drawn or written, with the plotting library's error.
#[derive(Debug, thiserror::Error)]
#[error("could not draw {}", path.display())]
pub struct PlotError {
    pub path: std::path::PathBuf,
    #[source]
    pub source: Box<dyn std::error::Error + Send + Sync>,
}

fn err<E: std::error::Error + Send + Sync + 'static>(path: &Path) -> impl Fn(E) -> PlotError + '_ {
    move |e| PlotError {
        path: path.to_path_buf(),
        source: Box::new(e),
    }
}

/// Plot range of a series: from the 0.2 % to the 99.8 % quantile of its finite values after the
/// first 5 % of samples, so a start-up spike does not flatten the rest.
fn range_of(vals: &[f64]) -> Range<f64> {
    let skip = vals.len() / 20;
    let mut v: Vec<f64> = vals[skip..].iter().copied().filter(|v| v.is_finite()).collect();
    if v.is_empty() {
        return -1.0..1.0;
    }
    v.sort_by(f64::total_cmp);
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    let (lo, hi) = (q(0.002), q(0.998));
    let pad = ((hi - lo) * 0.08).max(1e-3);
    (lo - pad)..(hi + pad)
}

/// One panel of a time series plot.
pub struct Series<'a> {
    pub label: &'a str,
    pub values: &'a [f64],
}

/// Stacked time series against `t`, with the window `[w0, w1]` shaded.
pub fn time_series(path: &Path, title: &str, t: &[f64], panels: &[Series], window: Option<[f64; 2]>) -> Result<(), PlotError> {
    fonts();
    let root = BitMapBackend::new(path, (1200, 360 * panels.len() as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(err(path))?;
    let areas = root.split_evenly((panels.len(), 1));
    let t_range = if t.is_empty() {
        0.0..1.0
    } else {
        t[0]..t[t.len() - 1].max(t[0] + 1e-9)
    };
    // Decimate to at most ~4000 points per panel.
    let stride = (t.len() / 4000).max(1);
    for (k, (area, p)) in areas.iter().zip(panels).enumerate() {
        let y = range_of(p.values);
        let mut chart = ChartBuilder::on(area)
            .caption(if k == 0 { title } else { "" }, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(t_range.clone(), y.clone())
            .map_err(err(path))?;
        chart
            .configure_mesh()
            .x_desc("t U/L")
            .y_desc(p.label)
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(err(path))?;
        if let Some([w0, w1]) = window {
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(w0, y.start), (w1, y.end)],
                    RGBColor(120, 170, 255).mix(0.25).filled(),
                )))
                .map_err(err(path))?
                .label("averaging window (whole periods)")
                .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 18, y + 5)], RGBColor(120, 170, 255).mix(0.25).filled()));
        }
        chart
            .draw_series(LineSeries::new(
                t.iter()
                    .zip(p.values)
                    .step_by(stride)
                    .filter(|(_, v)| v.is_finite())
                    .map(|(a, b)| (*a, b.clamp(y.start, y.end))),
                BLUE.stroke_width(1),
            ))
            .map_err(err(path))?
            .label(p.label)
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLUE));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(err(path))?;
    }
    root.present().map_err(err(path))?;
    Ok(())
}

/// Amplitude spectrum up to `f_max`, with vertical marks `(frequency, label, colour)`.
pub fn spectrum(
    path: &Path,
    title: &str,
    freqs: &[f64],
    amps: &[f64],
    f_max: f64,
    marks: &[(f64, String, RGBColor)],
) -> Result<(), PlotError> {
    fonts();
    let root = BitMapBackend::new(path, (1000, 500)).into_drawing_area();
    root.fill(&WHITE).map_err(err(path))?;
    let pts: Vec<(f64, f64)> = freqs
        .iter()
        .zip(amps)
        .filter(|(f, _)| **f <= f_max)
        .map(|(f, a)| (*f, *a))
        .collect();
    let a_max = pts.iter().map(|p| p.1).fold(0.0f64, f64::max).max(1e-12);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..f_max, 0.0..a_max * 1.1)
        .map_err(err(path))?;
    chart
        .configure_mesh()
        .x_desc("f L/U (Strouhal number)")
        .y_desc("|C_L| amplitude")
        .label_style(("sans-serif", 15))
        .draw()
        .map_err(err(path))?;
    chart
        .draw_series(LineSeries::new(pts, BLUE.stroke_width(2)))
        .map_err(err(path))?
        .label("lift spectrum")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLUE));
    for (f, label, colour) in marks {
        let c = *colour;
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(*f, 0.0), (*f, a_max * 1.1)],
                c.stroke_width(2),
            )))
            .map_err(err(path))?
            .label(label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(err(path))?;
    root.present().map_err(err(path))?;
    Ok(())
}

/// Diverging blue-white-red colour for `v` in `[-1, 1]`.
fn diverging(v: f64) -> RGBColor {
    let v = v.clamp(-1.0, 1.0);
    let lerp = |a: f64, b: f64, s: f64| (a + (b - a) * s).round() as u8;
    if v < 0.0 {
        let s = -v;
        RGBColor(lerp(255.0, 30.0, s), lerp(255.0, 60.0, s), lerp(255.0, 180.0, s))
    } else {
        RGBColor(lerp(255.0, 190.0, v), lerp(255.0, 30.0, v), lerp(255.0, 40.0, v))
    }
}

/// Writes `f` as a PNG colour map titled `label`, with a symmetric colour range at the 98th
/// percentile of |value| (so a few extremes do not wash out the rest).
pub fn field_png(f: &crate::flow::Field, path: &Path, label: &str) -> Result<(), PlotError> {
    let vmax = abs_quantile(&f.values, 0.98);
    let title = format!("{label} (colour range +-{vmax:.2})");
    field(path, &title, f.nx, f.ny, f.extent, &f.values, vmax)
}

/// Colour map of a field on `[x0, x1] x [y0, y1]` (row-major, `NaN` drawn grey), symmetric
/// colour range `+-vmax`.
pub fn field(path: &Path, title: &str, nx: usize, ny: usize, extent: [f64; 4], values: &[f32], vmax: f64) -> Result<(), PlotError> {
    fonts();
    let [x0, x1, y0, y1] = extent;
    let aspect = (y1 - y0) / (x1 - x0);
    let w = 1400u32;
    let h = ((w as f64 - 100.0) * aspect + 110.0).round().clamp(200.0, 1600.0) as u32;
    let root = BitMapBackend::new(path, (w, h)).into_drawing_area();
    root.fill(&WHITE).map_err(err(path))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err(path))?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x / L")
        .y_desc("y / L")
        .label_style(("sans-serif", 15))
        .draw()
        .map_err(err(path))?;
    let area = chart.plotting_area();
    let (pw, ph) = area.dim_in_pixel();
    let vmax = vmax.max(1e-12);
    for py in 0..ph {
        for px in 0..pw {
            let x = x0 + (px as f64 + 0.5) / pw as f64 * (x1 - x0);
            let y = y1 - (py as f64 + 0.5) / ph as f64 * (y1 - y0);
            let i = (((x - x0) / (x1 - x0)) * nx as f64).floor().clamp(0.0, (nx - 1) as f64) as usize;
            let j = (((y - y0) / (y1 - y0)) * ny as f64).floor().clamp(0.0, (ny - 1) as f64) as usize;
            let v = values[j * nx + i];
            let c = if v.is_finite() {
                diverging(v as f64 / vmax)
            } else {
                RGBColor(90, 90, 90)
            };
            area.draw_pixel((x, y), &c).map_err(err(path))?;
        }
    }
    root.present().map_err(err(path))?;
    Ok(())
}

/// A field (row-major from `y0` up, `NaN` grey) as an RGB image, `ny` rows of `nx` pixels with
/// the top row at `y1` (as a picture is read), symmetric colour range `+-vmax`: what an
/// environment's `render()` returns.
pub fn field_rgb(nx: usize, ny: usize, values: &[f32], vmax: f64) -> Vec<u8> {
    let vmax = vmax.max(1e-12);
    let mut rgb = Vec::with_capacity(nx * ny * 3);
    for j in (0..ny).rev() {
        for &v in &values[j * nx..(j + 1) * nx] {
            let RGBColor(r, g, b) = if v.is_finite() {
                diverging(v as f64 / vmax)
            } else {
                RGBColor(90, 90, 90)
            };
            rgb.extend([r, g, b]);
        }
    }
    rgb
}

/// The `q`-quantile of `|v|` over finite values (colour scales robust to a few extremes).
pub fn abs_quantile(values: &[f32], q: f64) -> f64 {
    let mut a: Vec<f32> = values.iter().filter(|v| v.is_finite()).map(|v| v.abs()).collect();
    if a.is_empty() {
        return 1.0;
    }
    let k = ((a.len() - 1) as f64 * q).round() as usize;
    let (_, v, _) = a.select_nth_unstable_by(k, |x, y| x.total_cmp(y));
    *v as f64
}

/// One line of a multi-line chart: points `(x, y)` (non-finite y are skipped), an optional
/// shaded band `y +- band` (e.g. the spread over seeds).
pub struct Line<'a> {
    pub label: &'a str,
    pub x: &'a [f64],
    pub y: &'a [f64],
    pub band: Option<&'a [f64]>,
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// Several lines in one panel with a legend (learning curves of several runs).
pub fn lines(path: &Path, title: &str, x_label: &str, y_label: &str, lines: &[Line]) -> Result<(), PlotError> {
    fonts();
    let root = BitMapBackend::new(path, (1100, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(err(path))?;
    let finite = |v: &f64| v.is_finite();
    let xs: Vec<f64> = lines.iter().flat_map(|l| l.x.iter().copied()).filter(finite).collect();
    let mut ys: Vec<f64> = vec![];
    for l in lines {
        for (i, y) in l.y.iter().enumerate() {
            let b = l.band.and_then(|b| b.get(i)).copied().unwrap_or(0.0);
            if y.is_finite() {
                ys.extend([y - b.abs(), y + b.abs()]);
            }
        }
    }
    let x0 = xs.iter().copied().fold(f64::INFINITY, f64::min);
    let x1 = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let x_range = if x0.is_finite() && x1 > x0 { x0..x1 } else { 0.0..1.0 };
    let y = if ys.is_empty() { -1.0..1.0 } else { range_of(&ys) };
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d(x_range, y.clone())
        .map_err(err(path))?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style(("sans-serif", 15))
        .draw()
        .map_err(err(path))?;
    for (k, l) in lines.iter().enumerate() {
        let c = PALETTE[k % PALETTE.len()];
        let pts: Vec<(f64, f64, f64)> =
            l.x.iter()
                .zip(l.y)
                .enumerate()
                .filter(|(_, (x, y))| x.is_finite() && y.is_finite())
                .map(|(i, (x, y))| (*x, *y, l.band.and_then(|b| b.get(i)).copied().unwrap_or(0.0).abs()))
                .collect();
        if l.band.is_some() && pts.len() > 1 {
            let mut poly: Vec<(f64, f64)> = pts
                .iter()
                .map(|(x, y, b)| (*x, (y + b).clamp(y_lo(&chart), y_hi(&chart))))
                .collect();
            poly.extend(pts.iter().rev().map(|(x, y, b)| (*x, (y - b).clamp(y_lo(&chart), y_hi(&chart)))));
            chart
                .draw_series(std::iter::once(Polygon::new(poly, c.mix(0.18).filled())))
                .map_err(err(path))?;
        }
        chart
            .draw_series(LineSeries::new(
                pts.iter().map(|(x, y, _)| (*x, y.clamp(y_lo(&chart), y_hi(&chart)))),
                c.stroke_width(2),
            ))
            .map_err(err(path))?
            .label(l.label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
        if pts.len() <= 60 {
            chart
                .draw_series(pts.iter().map(|(x, y, _)| Circle::new((*x, *y), 3, c.filled())))
                .map_err(err(path))?;
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(err(path))?;
    root.present().map_err(err(path))?;
    Ok(())
}

fn y_lo<DB: DrawingBackend>(
    c: &ChartContext<DB, Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>>,
) -> f64 {
    c.y_range().start
}

fn y_hi<DB: DrawingBackend>(
    c: &ChartContext<DB, Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>>,
) -> f64 {
    c.y_range().end
}

/// Bars with error whiskers (a leaderboard per environment): `(label, mean, std)`.
pub fn bars(path: &Path, title: &str, y_label: &str, bars: &[(String, f64, f64)]) -> Result<(), PlotError> {
    use plotters::coord::ranged1d::SegmentValue;
    fonts();
    let root = BitMapBackend::new(path, (200 + 140 * bars.len().max(1) as u32, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(err(path))?;
    let lo = bars.iter().map(|b| b.1 - b.2.abs()).fold(0.0, f64::min);
    let hi = bars.iter().map(|b| b.1 + b.2.abs()).fold(0.0, f64::max);
    let pad = ((hi - lo) * 0.1).max(1e-3);
    let n = bars.len().max(1) as i32;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(60)
        .y_label_area_size(80)
        .build_cartesian_2d((0..n).into_segmented(), (lo - pad)..(hi + pad))
        .map_err(err(path))?;
    let labels: Vec<String> = bars.iter().map(|b| b.0.clone()).collect();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(bars.len() + 1)
        .x_label_formatter(&|x| match x {
            SegmentValue::CenterOf(k) => labels.get(*k as usize).cloned().unwrap_or_default(),
            _ => String::new(),
        })
        .y_desc(y_label)
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err(path))?;
    for (k, (_, mean, std)) in bars.iter().enumerate() {
        let c = PALETTE[k % PALETTE.len()];
        let k = k as i32;
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(SegmentValue::Exact(k), 0.0), (SegmentValue::Exact(k + 1), *mean)],
                c.mix(0.8).filled(),
            )))
            .map_err(err(path))?;
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(SegmentValue::CenterOf(k), mean - std), (SegmentValue::CenterOf(k), mean + std)],
                BLACK.stroke_width(2),
            )))
            .map_err(err(path))?;
    }
    root.present().map_err(err(path))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_rgb_puts_the_top_of_the_domain_first_and_colours_by_sign() {
        // 2 x 2 field: bottom row (-1, NaN), top row (1, 0).
        let rgb = field_rgb(2, 2, &[-1.0, f32::NAN, 1.0, 0.0], 1.0);
        assert_eq!(rgb.len(), 12);
        assert_eq!(&rgb[0..3], &[190, 30, 40], "top-left: +1 is red");
        assert_eq!(&rgb[3..6], &[255, 255, 255], "top-right: 0 is white");
        assert_eq!(&rgb[6..9], &[30, 60, 180], "bottom-left: -1 is blue");
        assert_eq!(&rgb[9..12], &[90, 90, 90], "a body (NaN) is grey");
    }
}
