//! Pictures of a program in its cell (`prf view`), for users who want to look, not load a
//! viewer: from above (x–y) and from the side (x–z, looking along +y), with equal scales.
//! Drawn: the world's obstacles (grey), Ω+ of the pick and place locations projected (green,
//! one square per field node inside), the robot's collision spheres and platform box at
//! keyframes (outlines, coloured by time), the TCP path, and the part at its start and goal.

use crate::plots::Chart;
use anyhow::Result;
use nalgebra::Vector3;
use plotters::coord::Shift;
use plotters::prelude::*;
use prf_files::dataset::Sample;
use prf_shared::field::{DistanceField, Field};
use prf_shared::kinematics::{ArmKinematics, arm_base_pose, platform_pose};
use prf_shared::robot::{MAX_SPHERES, RobotModel};
use prf_shared::se3::Pose;

/// Which projection.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    /// x–y, from above.
    Top,
    /// x–z, from the side (looking along +y).
    Side,
}

impl Projection {
    fn project(self, p: &Vector3<f64>) -> (f64, f64) {
        match self {
            Projection::Top => (p.x, p.y),
            Projection::Side => (p.x, p.z),
        }
    }
}

/// A box: centre, yaw about z and half extents (world).
#[derive(Clone, Copy, Debug)]
pub struct Cuboid {
    pub centre: Vector3<f64>,
    pub yaw: f64,
    pub half: Vector3<f64>,
}

impl Cuboid {
    fn corners(&self) -> Vec<Vector3<f64>> {
        let (c, s) = (self.yaw.cos(), self.yaw.sin());
        let mut v = Vec::with_capacity(8);
        for sx in [-1.0, 1.0] {
            for sy in [-1.0, 1.0] {
                for sz in [-1.0, 1.0] {
                    let (x, y, z) = (sx * self.half.x, sy * self.half.y, sz * self.half.z);
                    v.push(self.centre + Vector3::new(c * x - s * y, s * x + c * y, z));
                }
            }
        }
        v
    }

    /// The outline of its projection (a rectangle's corners in order, or the projected
    /// bounding rectangle from the side).
    fn outline(&self, view: Projection) -> Vec<(f64, f64)> {
        let pts: Vec<(f64, f64)> = self.corners().iter().map(|p| view.project(p)).collect();
        match view {
            // The four bottom corners in ring order.
            Projection::Top => [0, 2, 6, 4].iter().map(|&i| pts[i]).collect(),
            Projection::Side => {
                let (x0, x1, y0, y1) = bounds(&pts);
                vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
            }
        }
    }
}

fn bounds(pts: &[(f64, f64)]) -> (f64, f64, f64, f64) {
    pts.iter().fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |(a, b, c, d), p| (a.min(p.0), b.max(p.0), c.min(p.1), d.max(p.1)),
    )
}

/// The size a part of type `kind` is drawn with: its world size, or a 5 cm cube for a type the
/// world does not size.
pub fn drawn_part_size(world: &prf_sim::world::World, kind: &str) -> [f64; 3] {
    let size = prf_sim::navigation::part_size(world, kind);
    if size.iter().all(|s| *s > 0.0) {
        size
    } else {
        [0.05; 3]
    }
}

/// The robot at one instant: its collision spheres (world centre, radius) and platform box.
struct RobotOutline {
    spheres: Vec<(Vector3<f64>, f64)>,
    platform: Cuboid,
}

fn robot_at(model: &RobotModel, s: &Sample) -> RobotOutline {
    let base = platform_pose(s.base);
    let kin = ArmKinematics::new(model, &s.arm.into());
    let mut centres = [Vector3::zeros(); MAX_SPHERES];
    kin.sphere_centres_in(model, &arm_base_pose(model, s.base), &mut centres);
    let spheres = model
        .spheres
        .iter()
        .zip(&centres)
        .map(|(sp, c)| (*c, sp.radius))
        .collect();
    let b = &model.platform;
    RobotOutline {
        spheres,
        platform: Cuboid {
            centre: base.transform_point(&b.centre.into()).coords,
            yaw: s.base[2],
            half: b.half_extents,
        },
    }
}

/// A learned workspace placed in the world.
pub struct PlacedField<'a> {
    pub name: String,
    pub location: Pose,
    pub field: Field<'a>,
}

/// A program in its cell, seen from above or from the side.
pub struct ProgramView<'a> {
    pub title: String,
    pub view: Projection,
    pub model: &'a RobotModel,
    pub samples: &'a [Sample],
    pub keyframes: usize,
    pub obstacles: &'a [Cuboid],
    pub fields: &'a [PlacedField<'a>],
    /// The part at its start and at its goal.
    pub part: [Cuboid; 2],
}

/// Colour of `t` in [0, 1]: blue (start) → orange → red (end).
fn time_colour(t: f64) -> RGBColor {
    let t = t.clamp(0.0, 1.0);
    let lerp = |a: f64, b: f64, f: f64| (a + (b - a) * f).round() as u8;
    if t < 0.5 {
        let f = t * 2.0;
        RGBColor(
            lerp(40.0, 240.0, f),
            lerp(90.0, 150.0, f),
            lerp(200.0, 30.0, f),
        )
    } else {
        let f = (t - 0.5) * 2.0;
        RGBColor(
            lerp(240.0, 190.0, f),
            lerp(150.0, 20.0, f),
            lerp(30.0, 40.0, f),
        )
    }
}

fn circle(c: (f64, f64), r: f64) -> Vec<(f64, f64)> {
    (0..=32)
        .map(|k| {
            let a = k as f64 / 32.0 * std::f64::consts::TAU;
            (c.0 + r * a.cos(), c.1 + r * a.sin())
        })
        .collect()
}

impl ProgramView<'_> {
    /// Keyframe sample indices: evenly over the program, first and last included.
    fn keyframe_indices(&self) -> Vec<usize> {
        let n = self.samples.len();
        let k = self.keyframes.max(2).min(n.max(1));
        (0..k).map(|i| i * (n - 1) / (k - 1).max(1)).collect()
    }

    /// The field nodes inside Ω+, projected, with the voxel size.
    fn workspace_points(&self) -> Vec<((f64, f64), f64)> {
        let mut out = Vec::new();
        for f in self.fields {
            let [nx, ny, nz] = f.field.dims();
            for i in 0..nx {
                for j in 0..ny {
                    for k in 0..nz {
                        let p = f.field.node_position(i, j, k);
                        if f.field.distance(&p) <= 0.0 {
                            let w = f.location.transform_point(&p.into()).coords;
                            out.push((self.view.project(&w), f.field.voxel()));
                        }
                    }
                }
            }
        }
        out
    }
}

impl Chart for ProgramView<'_> {
    fn size(&self) -> (u32, u32) {
        match self.view {
            Projection::Top => (1100, 900),
            Projection::Side => (1100, 560),
        }
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let keyframes: Vec<(f64, RobotOutline)> = self
            .keyframe_indices()
            .into_iter()
            .map(|i| {
                let t = i as f64 / (self.samples.len().max(2) - 1) as f64;
                (t, robot_at(self.model, &self.samples[i]))
            })
            .collect();
        let tcp: Vec<(f64, f64)> = self
            .samples
            .iter()
            .map(|s| {
                let p = arm_base_pose(self.model, s.base)
                    * ArmKinematics::new(self.model, &s.arm.into()).tcp;
                self.view.project(&p.translation.vector)
            })
            .collect();
        let workspace = self.workspace_points();
        // The extent of everything drawn, with equal scales on both axes.
        let mut pts: Vec<(f64, f64)> = tcp.clone();
        for (_, k) in &keyframes {
            pts.extend(k.spheres.iter().map(|(c, _)| self.view.project(c)));
            pts.extend(k.platform.outline(self.view));
        }
        pts.extend(workspace.iter().map(|(p, _)| *p));
        for c in self.part.iter() {
            pts.extend(c.outline(self.view));
        }
        if self.view == Projection::Side {
            pts.push((pts[0].0, 0.0));
        }
        let (x0, x1, y0, y1) = bounds(&pts);
        let pad = 0.3;
        let (mut x0, mut x1, mut y0, mut y1) = (x0 - pad, x1 + pad, y0 - pad, y1 + pad);
        let (w, h) = self.size();
        let (pw, ph) = (w as f64 - 90.0, h as f64 - 90.0);
        let scale = ((x1 - x0) / pw).max((y1 - y0) / ph);
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        (x0, x1) = (cx - scale * pw / 2.0, cx + scale * pw / 2.0);
        (y0, y1) = (cy - scale * ph / 2.0, cy + scale * ph / 2.0);

        root.fill(&WHITE)?;
        let (xl, yl) = match self.view {
            Projection::Top => ("x (m)", "y (m)"),
            Projection::Side => ("x (m)", "z (m)"),
        };
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc(xl)
            .y_desc(yl)
            .light_line_style(WHITE.mix(0.0))
            .draw()?;
        // Obstacles, clipped to the view.
        let grey = RGBColor(150, 150, 160);
        for o in self.obstacles {
            let outline = o.outline(self.view);
            let (a, b, c, d) = bounds(&outline);
            if b < x0 || a > x1 || d < y0 || c > y1 {
                continue;
            }
            chart.draw_series([Polygon::new(outline.clone(), grey.mix(0.35).filled())])?;
            let mut ring = outline;
            ring.push(ring[0]);
            chart.draw_series([PathElement::new(ring, grey.stroke_width(1))])?;
        }
        // Ω+ (projected).
        let green = RGBColor(60, 170, 80);
        chart.draw_series(workspace.iter().map(|((x, y), v)| {
            Rectangle::new(
                [(x - v / 2.0, y - v / 2.0), (x + v / 2.0, y + v / 2.0)],
                green.mix(0.08).filled(),
            )
        }))?;
        // The part at start (blue) and goal (green outline).
        for (c, colour) in self.part.iter().zip([RGBColor(40, 80, 220), green]) {
            let mut ring = c.outline(self.view);
            ring.push(ring[0]);
            chart.draw_series([PathElement::new(ring, colour.stroke_width(2))])?;
        }
        // The robot at keyframes.
        for (t, k) in &keyframes {
            let colour = time_colour(*t);
            let mut ring = k.platform.outline(self.view);
            ring.push(ring[0]);
            chart.draw_series([PathElement::new(ring, colour.mix(0.8).stroke_width(1))])?;
            chart.draw_series(k.spheres.iter().map(|(c, r)| {
                PathElement::new(
                    circle(self.view.project(c), *r),
                    colour.mix(0.6).stroke_width(1),
                )
            }))?;
        }
        chart
            .draw_series(LineSeries::new(tcp, BLACK.stroke_width(1)))?
            .label("TCP path")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.stroke_width(2)));
        for (name, colour) in [
            ("robot at the start", time_colour(0.0)),
            ("robot at the end", time_colour(1.0)),
            ("Ω+ (projected)", green),
        ] {
            chart
                .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(3))
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()?;
        Ok(())
    }
}
