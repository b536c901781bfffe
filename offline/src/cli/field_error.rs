//! `prf field-error`: how far each location type's learned Ω+ field lies above the exact Ω+
//! (the union of its dilated demonstrated balls), at random points near the boundary, and
//! which part of the representation the millimetres come from.

use crate::cli::progress::Bar;
use anyhow::Context;
use prf_files::dataset::Dataset;
use prf_files::robot;
use prf_learn::LearnConfig;
use prf_learn::learn::{Learner, learn_into};
use prf_learn::workspace::WorkspaceConfig;
use prf_offline::field_error::{BAND_BEYOND_EPSILON, Spread, measure};
use std::io::Write;
use std::path::PathBuf;

/// The field's goal: within this of the exact signed distance near the boundary, m.
const GOAL: f64 = 0.002;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Dataset directory (as written by `prf gen`); learned with the defaults of `prf learn`.
    pub dataset: PathBuf,
    /// Random points per location type, each within ε + 30 mm of Ω+'s boundary.
    #[arg(long, default_value_t = 2000)]
    pub points: usize,
    /// Workspace voxel (node spacing) to learn with, m (as `prf learn --voxel`).
    #[arg(long, default_value_t = WorkspaceConfig::default().voxel)]
    pub voxel: f64,
    /// Certification margin to learn with, m (as `prf learn --margin`).
    #[arg(long, default_value_t = WorkspaceConfig::default().certify_margin)]
    pub margin: f64,
    /// The demonstrated spheres are moved by up to this distance, mm.
    #[arg(long, default_value_t = 10.0)]
    pub moved_mm: f64,
    /// Seed of the points.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Also write every point's three distances (type, field, features, exact; m) as CSV.
    #[arg(long)]
    pub csv: Option<PathBuf>,
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let model = robot::example()?;
    let ds = Dataset::read(&a.dataset, &model)?;
    let mut cfg = LearnConfig::default();
    cfg.workspace.voxel = a.voxel;
    cfg.workspace.certify_margin = a.margin;
    let bar = Bar::new("learning", "units", false);
    let mut learner = Learner::new(&ds, &model, &cfg)?;
    let k = learn_into(&mut learner, &ds.demonstrations, &|p| bar.report(p))?;
    bar.finish();
    let eps = k.config.workspace.epsilon;
    let types = measure(&learner, &k, a.points, a.moved_mm * 1e-3, a.seed);
    println!(
        "Ω+ field ({:.0} mm voxel) against the exact Ω+ (every demonstrated ball, ε = {:.0} mm), \
         {} points per type within {:.0} mm of the boundary; mm, median / p95 / max",
        k.config.workspace.voxel * 1e3,
        eps * 1e3,
        a.points,
        (eps + BAND_BEYOND_EPSILON) * 1e3
    );
    let mm = |s: Spread| {
        format!(
            "{:.1} / {:.1} / {:.1}",
            s.median * 1e3,
            s.p95 * 1e3,
            s.max * 1e3
        )
    };
    println!(
        "{:<10} {:>8} {:>8} {:>22} {:>10} {:>22} {:>22} {:>12}",
        "type",
        "balls",
        "features",
        "field − exact",
        "≤ 2 mm",
        "grid + quantization",
        "thinning",
        "conservative"
    );
    for t in &types {
        let total = t.total();
        println!(
            "{:<10} {:>8} {:>8} {:>22} {:>9.1}% {:>22} {:>22} {:>12}",
            t.name,
            t.balls.0,
            t.balls.1,
            mm(total),
            100.0 * t.within(GOAL),
            mm(t.grid()),
            mm(t.thinning()),
            if total.min >= -1e-9 {
                "yes".to_string()
            } else {
                format!("NO ({:.3} mm)", total.min * 1e3)
            }
        );
    }
    println!(
        "grid + quantization: field − (min over the feature balls); thinning: (min over the \
         feature balls) − exact"
    );
    println!(
        "\ndemonstrated spheres moved by up to {:.0} mm ({} per type; margin {:.0} mm): the \
         risk term sdf + r_j (Eq. 16), mm, median / p95 / max",
        a.moved_mm,
        a.points,
        k.config.workspace.certify_margin * 1e3
    );
    println!(
        "{:<10} {:>22} {:>22} {:>22} {:>28}",
        "type", "field", "exact", "field − exact", "certified (of exact's)"
    );
    for t in &types {
        let (share, of) = t.moved_certified();
        println!(
            "{:<10} {:>22} {:>22} {:>22} {:>20.1}% of {:>5}",
            t.name,
            mm(Spread::of(t.moved.iter().map(|m| m.0).collect())),
            mm(Spread::of(t.moved.iter().map(|m| m.1).collect())),
            mm(Spread::of(t.moved.iter().map(|m| m.0 - m.1).collect())),
            100.0 * share,
            of
        );
    }
    if let Some(path) = &a.csv {
        let mut out = String::from("type,field_m,features_m,exact_m\n");
        for t in &types {
            for s in &t.samples {
                out += &format!("{},{},{},{}\n", t.name, s.field, s.features, s.exact);
            }
        }
        prf_files::atomic::write(path, out.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        std::io::stdout().flush()?;
        println!("wrote {}", path.display());
    }
    Ok(())
}
