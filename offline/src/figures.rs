//! Minimal SVG line plots (no dependencies): enough for a figure a person can open.

use std::fmt::Write as _;

/// One named polyline of (x, y) points.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    /// Emphasised (thicker, dark) line, e.g. the demonstration.
    pub emphasis: bool,
}

const PALETTE: [&str; 8] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#17becf",
];

/// Renders the series as an SVG line plot with axes, ticks, labels and a legend.
pub fn line_plot(title: &str, x_label: &str, y_label: &str, series: &[Series]) -> String {
    let (w, h, left, right, top, bottom) = (900.0, 540.0, 80.0, 220.0, 50.0, 60.0);
    let all = series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in all {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if !(x1 > x0) {
        x1 = x0 + 1.0;
    }
    let pad = ((y1 - y0) * 0.05).max(1e-9);
    (y0, y1) = (y0 - pad, y1 + pad);
    let px = |x: f64| left + (x - x0) / (x1 - x0) * (w - left - right);
    let py = |y: f64| h - bottom - (y - y0) / (y1 - y0) * (h - top - bottom);
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="13"><rect width="100%" height="100%" fill="white"/><text x="{}" y="28" font-size="16" text-anchor="middle">{title}</text>"#,
        (left + w - right) / 2.0
    );
    let _ = write!(
        s,
        r#"<rect x="{left}" y="{top}" width="{}" height="{}" fill="none" stroke="black"/>"#,
        w - left - right,
        h - top - bottom
    );
    for i in 0..=5 {
        let (xv, yv) = (
            x0 + (x1 - x0) * i as f64 / 5.0,
            y0 + (y1 - y0) * i as f64 / 5.0,
        );
        let _ = write!(
            s,
            r##"<line x1="{0}" y1="{1}" x2="{0}" y2="{2}" stroke="#ddd"/><text x="{0}" y="{3}" text-anchor="middle">{xv:.2}</text><line x1="{4}" y1="{5}" x2="{6}" y2="{5}" stroke="#ddd"/><text x="{7}" y="{8}" text-anchor="end">{yv:.3}</text>"##,
            px(xv),
            top,
            h - bottom,
            h - bottom + 18.0,
            left,
            py(yv),
            w - right,
            left - 6.0,
            py(yv) + 4.0
        );
    }
    let _ = write!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">{x_label}</text><text x="18" y="{}" text-anchor="middle" transform="rotate(-90 18 {})">{y_label}</text>"#,
        (left + w - right) / 2.0,
        h - 15.0,
        (top + h - bottom) / 2.0,
        (top + h - bottom) / 2.0
    );
    for (i, ser) in series.iter().enumerate() {
        let (color, width) = if ser.emphasis {
            ("#000", 3.0)
        } else {
            (PALETTE[i % PALETTE.len()], 1.5)
        };
        let pts: Vec<String> = ser
            .points
            .iter()
            .map(|&(x, y)| format!("{:.1},{:.1}", px(x), py(y)))
            .collect();
        let _ = write!(
            s,
            r#"<polyline fill="none" stroke="{color}" stroke-width="{width}" points="{}"/><line x1="{}" y1="{2}" x2="{3}" y2="{2}" stroke="{color}" stroke-width="{width}"/><text x="{4}" y="{5}">{6}</text>"#,
            pts.join(" "),
            w - right + 12.0,
            top + 12.0 + 20.0 * i as f64,
            w - right + 36.0,
            w - right + 42.0,
            top + 16.0 + 20.0 * i as f64,
            ser.name
        );
    }
    s.push_str("</svg>\n");
    s
}
