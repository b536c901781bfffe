//! Writes the seed corpora of every fuzz target into `<fuzz dir>/seeds/<target>/` (see
//! `prf_fuzz::seeds`). Run by `scripts/fuzz.sh seeds` after it has copied a freshly learned
//! blob to `fuzz/data/smoke.blob`.

use clap::Parser;
use std::path::PathBuf;

/// Writes the fuzz targets' seed corpora from real files.
#[derive(Parser)]
struct Args {
    /// The example dataset the blob was learned from (`prf gen --only 0-1,20,60`).
    #[arg(long)]
    dataset: PathBuf,
    /// The fuzz directory.
    #[arg(short, long, default_value = "fuzz")]
    out: PathBuf,
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    let seeds = prf_fuzz::seeds::all(&args.dataset)?;
    for (target, name, bytes) in &seeds {
        let dir = args.out.join("seeds").join(target);
        std::fs::create_dir_all(&dir)?;
        std::fs::write(dir.join(name), bytes)?;
    }
    println!(
        "{} seeds written under {}",
        seeds.len(),
        args.out.join("seeds").display()
    );
    Ok(())
}
