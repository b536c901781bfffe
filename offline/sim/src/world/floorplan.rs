//! Top view of a cell as SVG: obstacle footprints, stances, and the platform and TCP paths of
//! a dataset's programs — where a picture beats a table.

use super::geometry::Cell;
use super::{World, planar};
use prf_files::dataset::Demonstration;
use prf_shared::JointVector;
use prf_shared::kinematics::{ArmKinematics, arm_base_pose};
use std::fmt::Write as _;

/// Pixels per metre.
const SCALE: f64 = 90.0;
const MARGIN: f64 = 0.8;

/// Renders the cell and the programs' platform paths (blue) and TCP paths (orange).
pub fn floorplan_svg(world: &World, cell: &Cell, demos: &[Demonstration]) -> String {
    let boxes: Vec<_> = cell.obstacles.iter().map(|o| o.footprint()).collect();
    let mut stances = Vec::new();
    for (i, loc) in world.locations.iter().enumerate() {
        for a in &world.location_type(i).approaches {
            let p = world.location_pose(i) * a.stance.pose();
            stances.push((
                format!("{}.{}", loc.id, a.name),
                cell.platform_footprint(planar(&p)),
            ));
        }
    }
    let (mut x0, mut x1, mut y0, mut y1) = (world.home.x, world.home.x, world.home.y, world.home.y);
    for c in boxes.iter().chain(stances.iter().map(|s| &s.1)).flatten() {
        (x0, x1, y0, y1) = (x0.min(c.x), x1.max(c.x), y0.min(c.y), y1.max(c.y));
    }
    (x0, x1, y0, y1) = (x0 - MARGIN, x1 + MARGIN, y0 - MARGIN, y1 + MARGIN);
    let (w, h) = ((x1 - x0) * SCALE, (y1 - y0) * SCALE + 40.0);
    let px = |x: f64| (x - x0) * SCALE;
    let py = |y: f64| 40.0 + (y1 - y) * SCALE;
    let poly = |pts: &[nalgebra::Vector2<f64>]| {
        pts.iter()
            .map(|p| format!("{:.1},{:.1}", px(p.x), py(p.y)))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0}" height="{h:.0}" font-family="sans-serif" font-size="12"><rect width="100%" height="100%" fill="white"/><text x="10" y="24" font-size="15">{} — top view, {} programs (platform path blue, TCP path orange, grid 1 m)</text>"#,
        escape(&world.source.display().to_string()),
        demos.len()
    );
    // 1 m grid.
    for gx in (x0.ceil() as i64)..=(x1.floor() as i64) {
        let _ = write!(
            s,
            r##"<line x1="{0:.1}" y1="40" x2="{0:.1}" y2="{h:.0}" stroke="#eee"/>"##,
            px(gx as f64)
        );
    }
    for gy in (y0.ceil() as i64)..=(y1.floor() as i64) {
        let _ = write!(
            s,
            r##"<line x1="0" y1="{0:.1}" x2="{w:.0}" y2="{0:.1}" stroke="#eee"/>"##,
            py(gy as f64)
        );
    }
    for b in &boxes {
        let _ = write!(
            s,
            r##"<polygon points="{}" fill="#555" fill-opacity="0.25" stroke="#333" stroke-width="0.5"/>"##,
            poly(b)
        );
    }
    for (name, f) in &stances {
        let _ = write!(
            s,
            r##"<polygon points="{}" fill="none" stroke="#2a7" stroke-dasharray="4 3"/>"##,
            poly(f)
        );
        let c = (f[0] + f[2]) / 2.0;
        let _ = write!(
            s,
            r##"<text x="{:.1}" y="{:.1}" fill="#2a7" font-size="10" text-anchor="middle">{name}</text>"##,
            px(c.x),
            py(c.y) + 4.0
        );
    }
    let model = &cell.model;
    for d in demos {
        let step = (d.samples.len() / 600).max(1);
        let base: Vec<String> = d
            .samples
            .iter()
            .step_by(step)
            .map(|s| format!("{:.1},{:.1}", px(s.base[0]), py(s.base[1])))
            .collect();
        let tcp: Vec<String> = d
            .samples
            .iter()
            .step_by(step)
            .map(|s| {
                let p = arm_base_pose(model, s.base)
                    * ArmKinematics::new(model, &JointVector::from(s.arm)).tcp;
                format!("{:.1},{:.1}", px(p.translation.x), py(p.translation.y))
            })
            .collect();
        let _ = write!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#1f77b4" stroke-opacity="0.35"/>"##,
            base.join(" ")
        );
        let _ = write!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#ff7f0e" stroke-opacity="0.5" stroke-width="0.8"/>"##,
            tcp.join(" ")
        );
    }
    for (i, loc) in world.locations.iter().enumerate() {
        let p = world.location_pose(i).translation;
        let _ = write!(
            s,
            r#"<text x="{:.1}" y="{:.1}" font-weight="bold" text-anchor="middle">{}</text>"#,
            px(p.x),
            py(p.y) + if p.y < world.home.y { 16.0 } else { -6.0 },
            loc.id
        );
    }
    let _ = write!(
        s,
        r##"<circle cx="{:.1}" cy="{:.1}" r="5" fill="#d62728"/><text x="{:.1}" y="{:.1}" fill="#d62728">home</text></svg>"##,
        px(world.home.x),
        py(world.home.y),
        px(world.home.x) + 8.0,
        py(world.home.y) - 6.0
    );
    s
}

/// Escapes text for XML.
fn escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
