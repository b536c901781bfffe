//! `prf inspect`: validates a blob (header, version, CRC-32, every record) and prints its
//! contents and sizes by section.

use crate::cli::args::read_blob;
use anyhow::Context;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Blob file.
    pub blob: PathBuf,
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    let bytes = read_blob(&a.blob)?;
    let r = prf_learn::report(&bytes).with_context(|| format!("{}", a.blob.display()))?;
    print!("{r}");
    Ok(())
}
