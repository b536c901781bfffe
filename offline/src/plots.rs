//! Charts (plotters), each written twice: `NAME.svg` and `NAME.png`, text set in a TrueType
//! font found at run time ([`FONT_PATHS`] or `$PRF_FONT`).
//!
//! - [`LinePlot`]: named polylines, one emphasised (the paper's Fig. 3iv, the elbow);
//! - [`HeatMap`]: a value per cell of a regular grid, cells without a value crossed out
//!   (Fig. 3ii, the risk over new goals);
//! - [`Histogram`]: overlaid histograms of two or more samples (Fig. 3iii);
//! - [`BandPlot`]: per series a mean line over a min–max band (Fig. 5);
//! - [`ScalingPlot`]: a figure against a count, each count ticked (`prf bench-learn`).

use anyhow::{Context, Result, anyhow};
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Where the font is looked for, after `$PRF_FONT` (Debian's `fonts-dejavu-core`).
pub const FONT_PATHS: [&str; 2] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

/// Registers the font for the family "sans-serif" once per process.
fn register_font() -> Result<()> {
    static DONE: OnceLock<Result<(), String>> = OnceLock::new();
    DONE.get_or_init(|| {
        let candidates: Vec<PathBuf> = std::env::var_os("PRF_FONT")
            .map(PathBuf::from)
            .into_iter()
            .chain(FONT_PATHS.iter().map(PathBuf::from))
            .collect();
        let Some((path, bytes)) = candidates
            .iter()
            .find_map(|p| std::fs::read(p).ok().map(|b| (p, b)))
        else {
            return Err(format!(
                "no font to set chart text in: looked for {}; install Debian's fonts-dejavu-core or set PRF_FONT to a .ttf file",
                candidates
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        };
        // Fonts live as long as the process (plotters keeps &'static references).
        let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
            .map_err(|_| format!("{} is not a TrueType font", path.display()))
    })
    .clone()
    .map_err(|e| anyhow!(e))
}

/// A chart that can be drawn on any plotters backend.
pub trait Chart {
    /// Pixel size (width, height).
    fn size(&self) -> (u32, u32) {
        (900, 540)
    }
    /// Draws the chart on `root`.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static;
}

/// Writes `chart` as `stem.svg` and `stem.png`, each whole or not at all (drawn into a
/// temporary file beside it, then renamed); returns both paths.
pub fn save(chart: &impl Chart, stem: &Path) -> Result<[PathBuf; 2]> {
    register_font()?;
    let svg = stem.with_extension("svg");
    let png = stem.with_extension("png");
    let size = chart.size();
    atomically(&svg, |p| {
        present(chart, SVGBackend::new(p, size).into_drawing_area())
    })?;
    atomically(&png, |p| {
        present(chart, BitMapBackend::new(p, size).into_drawing_area())
    })?;
    Ok([svg, png])
}

/// Runs `write` on a temporary path beside `target`, then renames it over `target`.
fn atomically(target: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let context = || format!("writing {}", target.display());
    let tmp = prf_files::atomic::temp_beside(target).with_context(context)?;
    write(tmp.path()).with_context(context)?;
    prf_files::atomic::persist(tmp, target).with_context(context)
}

/// Draws `chart` on `root` and writes it out.
fn present<DB: DrawingBackend>(chart: &impl Chart, root: DrawingArea<DB, Shift>) -> Result<()>
where
    DB::ErrorType: 'static,
{
    chart.draw(&root)?;
    root.present()?;
    Ok(())
}

/// A count's tick label: whole values only (a tick between two counts stays blank).
fn whole(v: &f64) -> String {
    if (v - v.round()).abs() < 1e-9 {
        format!("{:.0}", v)
    } else {
        String::new()
    }
}

/// The range of `values` with 5 % padding (a unit range when they are all equal or none).
fn padded(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !(hi > lo) {
        let c = if lo.is_finite() { lo } else { 0.0 };
        return c - 0.5..c + 0.5;
    }
    let pad = (hi - lo) * 0.05;
    lo - pad..hi + pad
}

/// Draws the legend of `chart`'s labelled series in a framed box at `position`.
fn legend<'a, DB: DrawingBackend + 'a, Y: Ranged>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
    position: SeriesLabelPosition,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(position)
        .draw()?;
    Ok(())
}

/// One named polyline of (x, y) points.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    /// Emphasised (thicker, black) line, e.g. the demonstration.
    pub emphasis: bool,
    /// Palette index of its colour (series of one kind share one).
    pub colour: usize,
}

/// Polylines with a title, labelled axes and a legend (series with an empty name stay out of
/// it).
pub struct LinePlot<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub series: &'a [Series],
}

impl Chart for LinePlot<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let points = || self.series.iter().flat_map(|s| s.points.iter());
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(root)
            .caption(self.title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(padded(points().map(|p| p.0)), padded(points().map(|p| p.1)))?;
        chart
            .configure_mesh()
            .x_desc(self.x_label)
            .y_desc(self.y_label)
            .light_line_style(WHITE.mix(0.0))
            .draw()?;
        // Emphasised series last, on top.
        let order = self
            .series
            .iter()
            .enumerate()
            .filter(|(_, s)| !s.emphasis)
            .chain(self.series.iter().enumerate().filter(|(_, s)| s.emphasis));
        let mut labelled = false;
        // Many overlapping lines stay readable when each is translucent.
        let alpha = if self.series.len() > 20 { 0.3 } else { 1.0 };
        for (_, s) in order {
            let style = if s.emphasis {
                BLACK.stroke_width(3)
            } else {
                Palette99::pick(s.colour).mix(alpha).stroke_width(1)
            };
            let drawn = chart.draw_series(LineSeries::new(s.points.iter().copied(), style))?;
            if !s.name.is_empty() {
                labelled = true;
                drawn.label(s.name.as_str()).legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], style.color.mix(1.0).stroke_width(2))
                });
            }
        }
        if labelled {
            legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        }
        Ok(())
    }
}

/// Colour of `t` in [0, 1] on a white → orange → dark red scale.
fn heat(t: f64) -> RGBColor {
    let stops = [
        (255.0, 255.0, 255.0),
        (253.0, 141.0, 60.0),
        (128.0, 0.0, 38.0),
    ];
    let t = t.clamp(0.0, 1.0) * 2.0;
    let (i, f) = if t >= 2.0 {
        (1, 1.0)
    } else {
        (t as usize, t.fract())
    };
    let (a, b) = (stops[i], stops[i + 1]);
    let mix = |x: f64, y: f64| (x + (y - x) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// A value per cell of a regular grid (`values[j * xs.len() + i]` at `(xs[i], ys[j])`, cell
/// centres), coloured from 0 to `max`; cells without a value are grey and crossed out. An
/// optional marker shows a point (the demonstrated goal).
pub struct HeatMap<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    /// What the colour shows, with its unit.
    pub value_label: &'a str,
    pub xs: &'a [f64],
    pub ys: &'a [f64],
    pub values: &'a [Option<f64>],
    /// The value of the darkest colour (larger values saturate).
    pub max: f64,
    pub marker: Option<(f64, f64)>,
}

impl Chart for HeatMap<'_> {
    fn size(&self) -> (u32, u32) {
        (760, 620)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let half = |v: &[f64]| {
            if v.len() > 1 {
                (v[1] - v[0]) / 2.0
            } else {
                0.5
            }
        };
        let (hx, hy) = (half(self.xs), half(self.ys));
        let (x0, x1) = (self.xs[0] - hx, self.xs[self.xs.len() - 1] + hx);
        let (y0, y1) = (self.ys[0] - hy, self.ys[self.ys.len() - 1] + hy);
        root.fill(&WHITE)?;
        let (plot, bar) = root.split_horizontally(root.dim_in_pixel().0 - 110);
        let mut chart = ChartBuilder::on(&plot)
            .caption(self.title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc(self.x_label)
            .y_desc(self.y_label)
            .disable_mesh()
            .draw()?;
        let max = if self.max > 0.0 { self.max } else { 1.0 };
        for (j, &y) in self.ys.iter().enumerate() {
            for (i, &x) in self.xs.iter().enumerate() {
                let cell = [(x - hx, y - hy), (x + hx, y + hy)];
                match self.values.get(j * self.xs.len() + i).copied().flatten() {
                    Some(v) => {
                        chart.draw_series([Rectangle::new(cell, heat(v / max).filled())])?;
                    }
                    None => {
                        chart.draw_series([Rectangle::new(
                            cell,
                            RGBColor(200, 200, 200).filled(),
                        )])?;
                        chart.draw_series([PathElement::new(cell.to_vec(), BLACK.mix(0.4))])?;
                    }
                }
            }
        }
        if let Some(m) = self.marker {
            chart.draw_series([Cross::new(m, 8, BLACK.stroke_width(2))])?;
        }
        // Colour bar.
        let mut scale = ChartBuilder::on(&bar)
            .margin_top(40)
            .margin_bottom(52)
            .margin_right(8)
            .y_label_area_size(50)
            .build_cartesian_2d(0.0..1.0, 0.0..max)?;
        scale
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc(self.value_label)
            .y_label_style(("sans-serif", 12))
            .axis_desc_style(("sans-serif", 13))
            .draw()?;
        let steps = 64;
        scale.draw_series((0..steps).map(|k| {
            let (a, b) = (k as f64 / steps as f64, (k + 1) as f64 / steps as f64);
            Rectangle::new([(0.0, a * max), (1.0, b * max)], heat(a).filled())
        }))?;
        Ok(())
    }
}

/// Overlaid histograms of named samples over common bins of `[0, max]` (values above `max`
/// fall in the last bin).
pub struct Histogram<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub samples: &'a [(&'a str, Vec<f64>)],
    pub bins: usize,
    pub max: f64,
}

impl Histogram<'_> {
    /// Counts per bin of each sample.
    pub fn counts(&self) -> Vec<Vec<usize>> {
        let width = self.max / self.bins as f64;
        self.samples
            .iter()
            .map(|(_, v)| {
                let mut c = vec![0; self.bins];
                for x in v {
                    let b = ((x / width).floor().max(0.0) as usize).min(self.bins - 1);
                    c[b] += 1;
                }
                c
            })
            .collect()
    }
}

impl Chart for Histogram<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let counts = self.counts();
        let top = counts.iter().flatten().copied().max().unwrap_or(1).max(1) as u32;
        let width = self.max / self.bins as f64;
        // The samples' bars side by side within each bin, so none hides another.
        let bar = width / self.samples.len().max(1) as f64;
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(root)
            .caption(self.title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..self.max, 0u32..top + top / 12 + 1)?;
        chart
            .configure_mesh()
            .x_desc(self.x_label)
            .y_desc("goals")
            .light_line_style(WHITE.mix(0.0))
            .draw()?;
        for (s, ((name, _), c)) in self.samples.iter().zip(&counts).enumerate() {
            let colour = Palette99::pick(s);
            chart
                .draw_series(c.iter().enumerate().map(|(b, &n)| {
                    let x = b as f64 * width + s as f64 * bar;
                    Rectangle::new([(x, 0), (x + bar, n as u32)], colour.mix(0.8).filled())
                }))?
                .label(*name)
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 16, y + 5)], colour.filled())
                });
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)?;
        Ok(())
    }
}

/// A series of the band plot: per x its mean, minimum and maximum.
pub struct Band {
    pub name: String,
    /// (x, mean, min, max).
    pub points: Vec<(f64, f64, f64, f64)>,
}

/// Mean lines over min–max bands: counts against counts, so both axes tick whole numbers.
pub struct BandPlot<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub bands: &'a [Band],
    /// Horizontal reference lines (value, label), e.g. the total count.
    pub references: &'a [(f64, String)],
}

impl Chart for BandPlot<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let xs = padded(self.bands.iter().flat_map(|b| b.points.iter().map(|p| p.0)));
        let top = self
            .bands
            .iter()
            .flat_map(|b| b.points.iter().map(|p| p.3))
            .chain(self.references.iter().map(|r| r.0))
            .fold(1.0f64, f64::max);
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(root)
            .caption(self.title, ("sans-serif", 18))
            .margin(24)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(xs.clone(), 0.0..top * 1.08)?;
        chart
            .configure_mesh()
            .x_desc(self.x_label)
            .y_desc(self.y_label)
            .x_label_formatter(&whole)
            .y_label_formatter(&whole)
            .light_line_style(WHITE.mix(0.0))
            .draw()?;
        for (value, label) in self.references {
            chart.draw_series([PathElement::new(
                vec![(xs.start, *value), (xs.end, *value)],
                BLACK.mix(0.5),
            )])?;
            // Above its line (a text hangs below the point it is placed at).
            chart.draw_series([Text::new(
                label.clone(),
                (xs.start + (xs.end - xs.start) * 0.01, value + top * 0.045),
                ("sans-serif", 13),
            )])?;
        }
        for (s, b) in self.bands.iter().enumerate() {
            let colour = Palette99::pick(s);
            let outline: Vec<(f64, f64)> = b
                .points
                .iter()
                .map(|p| (p.0, p.3))
                .chain(b.points.iter().rev().map(|p| (p.0, p.2)))
                .collect();
            chart.draw_series([Polygon::new(outline, colour.mix(0.25).filled())])?;
            chart
                .draw_series(LineSeries::new(
                    b.points.iter().map(|p| (p.0, p.1)),
                    colour.stroke_width(2),
                ))?
                .label(b.name.as_str())
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2))
                });
        }
        legend(&mut chart, SeriesLabelPosition::LowerRight)?;
        Ok(())
    }
}

/// A measured value against a count (a figure against the number of programs): the counts
/// evenly spaced and ticked as they are (sizes that grow by a factor each are spaced as on a
/// logarithmic axis), a line through the points, each marked and labelled with its value.
pub struct ScalingPlot<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    /// Legend entry of the line.
    pub name: &'a str,
    /// (count, value), ascending counts.
    pub points: &'a [(usize, f64)],
}

impl Chart for ScalingPlot<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let k = self.points.len().max(1);
        let top = self.points.iter().map(|p| p.1).fold(0.0, f64::max);
        let top = if top > 0.0 { top * 1.2 } else { 1.0 };
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(root)
            .caption(self.title, ("sans-serif", 18))
            .margin(24)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d((0..k - 1).into_segmented(), 0.0..top)?;
        let count = |x: &SegmentValue<usize>| match x {
            SegmentValue::CenterOf(i) | SegmentValue::Exact(i) => self
                .points
                .get(*i)
                .map_or_else(String::new, |p| p.0.to_string()),
            SegmentValue::Last => String::new(),
        };
        chart
            .configure_mesh()
            .x_desc(self.x_label)
            .y_desc(self.y_label)
            .x_labels(k)
            .x_label_formatter(&count)
            .light_line_style(WHITE.mix(0.0))
            .draw()?;
        let colour = Palette99::pick(0).to_rgba();
        let line = self
            .points
            .iter()
            .enumerate()
            .map(|(i, p)| (SegmentValue::CenterOf(i), p.1));
        chart
            .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))?
            .label(self.name)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2)));
        chart.draw_series(line.map(|(x, v)| {
            EmptyElement::at((x, v))
                + Circle::new((0, 0), 4, colour.filled())
                + Text::new(format!("{v:.1}"), (8, -20), ("sans-serif", 14).into_font())
        }))?;
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperLeft)
            .draw()?;
        Ok(())
    }
}
