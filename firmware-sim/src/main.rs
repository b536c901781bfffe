//! `prf-firmware-sim`: the simulated iiwa joint controller as a process of its own.

use clap::Parser;

#[derive(Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(flatten)]
    args: prf_firmware_sim::cli::Args,
}

fn main() -> anyhow::Result<()> {
    Ok(prf_firmware_sim::cli::run(&Cli::parse().args)?)
}
