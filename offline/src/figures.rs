//! Charts as SVG files (plotters), for a figure a person can open.

use plotters::prelude::*;

/// One named polyline of (x, y) points.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    /// Emphasised (thicker, black) line, e.g. the demonstration.
    pub emphasis: bool,
}

/// The range of `values` with 5 % padding (a unit range when they are all equal or none).
fn padded(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if !(hi > lo) {
        let c = if lo.is_finite() { lo } else { 0.0 };
        return c - 0.5..c + 0.5;
    }
    let pad = (hi - lo) * 0.05;
    lo - pad..hi + pad
}

/// The series as an SVG line plot with a title, labelled axes, a grid and a legend.
pub fn line_plot(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> anyhow::Result<String> {
    let points = || series.iter().flat_map(|s| s.points.iter());
    let xs = padded(points().map(|p| p.0));
    let ys = padded(points().map(|p| p.1));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 540)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(xs, ys)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .light_line_style(WHITE.mix(0.0))
            .draw()?;
        for (i, s) in series.iter().enumerate() {
            let style = if s.emphasis {
                BLACK.stroke_width(3)
            } else {
                Palette99::pick(i).stroke_width(1)
            };
            chart
                .draw_series(LineSeries::new(s.points.iter().copied(), style))?
                .label(s.name.as_str())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], style));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()?;
        root.present()?;
    }
    Ok(svg)
}
