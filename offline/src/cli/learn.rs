//! `prf learn`: Learn (Alg. 3) on a dataset and compile the blob.

use crate::cli::progress::Bar;
use anyhow::Context;
use prf_files::dataset::Dataset;
use prf_files::robot;
use prf_learn::{LearnConfig, compile, learn, learn::skills_per_class, report};
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Dataset directory (as written by `prf gen`).
    pub dataset: PathBuf,
    /// Output blob.
    #[arg(short, long, default_value = "cell.blob")]
    pub output: PathBuf,
    /// Robot URDF; default: the example cell's KMR iiwa 14 (offline/data/kmr_iiwa14.urdf).
    #[arg(long, requires = "spheres")]
    pub urdf: Option<PathBuf>,
    /// Collision-sphere file for --urdf (offline/data/kmr_iiwa14.spheres.json format).
    #[arg(long, requires = "urdf")]
    pub spheres: Option<PathBuf>,
    /// r_d, m: by default the dataset's stated clearance (manifest `clearance_demo_m`); a
    /// smaller value is more conservative, a larger one is refused.
    #[arg(long)]
    pub clearance_demo: Option<f64>,
    /// True acceptable clearance r, m (workspaces are dilated by ε = r_d − r).
    #[arg(long, default_value_t = 0.03)]
    pub clearance: f64,
    /// Workspace voxel (node spacing), m.
    #[arg(long, default_value_t = 0.05)]
    pub voxel: f64,
    /// Bricks whose nodes are all at least this far outside Ω+ store one value, m.
    #[arg(long, default_value_t = 0.08)]
    pub far: f64,
    /// Every demonstrated sphere is certified with this margin, m.
    #[arg(long, default_value_t = 0.001)]
    pub margin: f64,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let model = match (&a.urdf, &a.spheres) {
        (Some(u), Some(s)) => robot::load(u, s)?,
        _ => robot::example()?,
    };
    let ds = Dataset::read(&a.dataset, &model)?;
    let t_read = t0.elapsed().as_secs_f64();
    let mut cfg = LearnConfig {
        clearance_demo: a.clearance_demo,
        clearance_acceptable: a.clearance,
        ..LearnConfig::default()
    };
    cfg.workspace.voxel = a.voxel;
    cfg.workspace.far = a.far;
    cfg.workspace.certify_margin = a.margin;
    let bar = Bar::new("learning", "units", a.quiet);
    let t1 = Instant::now();
    let k = learn(&ds, &model, &cfg, &|p| bar.report(p))?;
    let t_learn = t1.elapsed().as_secs_f64();
    bar.finish();
    let t2 = Instant::now();
    let bytes = compile(&k)?;
    let t_compile = t2.elapsed().as_secs_f64();
    prf_files::atomic::write(&a.output, &bytes)
        .with_context(|| format!("writing {}", a.output.display()))?;
    if a.quiet {
        return Ok(());
    }
    println!(
        "learned from {} demonstrations in {}: {}",
        k.demonstrations,
        a.dataset.display(),
        k.instances
            .iter()
            .map(|(c, n)| format!("{n} {c}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for (c, n, shared) in skills_per_class(&k) {
        println!("  K_{c}: {n} skills ({shared} from share())");
    }
    for l in &k.location_types {
        if let Some(f) = &l.field {
            println!(
                "  Ω+ {}: {} demonstrated spheres from {} instances, {} feature balls",
                l.name, f.spheres, l.instances, f.feature_balls
            );
        }
    }
    print!("{}", report(&bytes)?);
    println!(
        "time: read {t_read:.2} s, learn {t_learn:.2} s ({}), compile {t_compile:.3} s",
        k.timings
            .iter()
            .map(|(n, t)| format!("{n} {t:.2} s"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    println!("wrote {}", a.output.display());
    Ok(())
}
