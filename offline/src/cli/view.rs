//! `prf view`: a planned program in its cell as pictures (PNG and SVG), from above and from
//! the side (`prf_offline::view`).

use crate::cli::args::{TaskArgs, WorldArgs, read_blob, runtime};
use anyhow::{Context, bail};
use nalgebra::Vector3;
use prf_offline::plots::save;
use prf_offline::view::{Cuboid, PlacedField, ProgramView, Projection, drawn_part_size};
use prf_runtime::RuntimeConfig;
use prf_runtime::plan::plan;
use prf_shared::se3::Pose;
use prf_sim::world::geometry::Cell;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The blob (from `prf learn`).
    pub blob: PathBuf,
    /// The task (all three of --part, --from, --to).
    #[command(flatten)]
    pub task: TaskArgs,
    /// The world: floor plan, locations and the obstacles drawn (default: the built-in
    /// example).
    #[command(flatten)]
    pub world: WorldArgs,
    /// Instants at which the robot is drawn, evenly over the program.
    #[arg(long, default_value_t = 10)]
    pub keyframes: usize,
    /// Directory for top.png/.svg and side.png/.svg.
    #[arg(short, long)]
    pub out: PathBuf,
}

fn cuboid(pose: &Pose, size: [f64; 3]) -> Cuboid {
    Cuboid {
        centre: pose.translation.vector,
        yaw: pose.rotation.euler_angles().2,
        half: Vector3::from(size) / 2.0,
    }
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let world = a.world.load()?;
    let bytes = read_blob(&a.blob)?;
    let rt = runtime(&bytes, &a.blob, RuntimeConfig::default())?;
    let ft = a.task.required(&world)?;
    let p = plan(&rt, &ft.task()).map_err(|e| anyhow::anyhow!("task {}: {e}", ft.label()))?;
    let Some(program) = &p.program else {
        bail!(
            "task {}: no program to draw: no skill integrates for it",
            ft.label()
        );
    };
    let samples = crate::cli::plan::execute(&world, &rt, &ft, program)?;
    let obstacles: Vec<Cuboid> = Cell::new(&world, &rt.model)
        .obstacles
        .iter()
        .map(|o| {
            let (centre, yaw, half) = o.cuboid();
            Cuboid { centre, yaw, half }
        })
        .collect();
    let mut fields = Vec::new();
    for (name, location, t) in [
        (&ft.from.0, ft.from_pose, p.resolved.from_type),
        (&ft.to.0, ft.to_pose, p.resolved.to_type),
    ] {
        if let Some(field) = rt.workspace(t)? {
            fields.push(PlacedField {
                name: name.clone(),
                location,
                field,
            });
        }
    }
    let size = drawn_part_size(&world, &ft.part.1);
    let part = [cuboid(&ft.part_pose, size), cuboid(&ft.goal, size)];
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let j = p.skills.j;
    for (view, name, what) in [
        (Projection::Top, "top", "from above"),
        (Projection::Side, "side", "from the side (looking along +y)"),
    ] {
        let chart = ProgramView {
            title: format!(
                "{}: {what}, J* = {:.1} mm, {:.1} s",
                ft.label(),
                j * 1e3,
                samples.len() as f64 * rt.config.rdmp.dt
            ),
            view,
            model: &rt.model,
            samples: &samples,
            keyframes: a.keyframes,
            obstacles: &obstacles,
            fields: &fields,
            part,
        };
        let [svg, png] = save(&chart, &a.out.join(name))?;
        println!("{} and {}", svg.display(), png.display());
    }
    Ok(())
}
