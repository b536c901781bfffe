//! Command-line options of the controller (the `prf-firmware-sim` binary and
//! `prf firmware-sim` share them).

use crate::controller::{self, Config};
use crate::servo::ServoConfig;
use prf_sim::world::World;
use std::path::PathBuf;

/// Simulated KUKA iiwa joint controller: tracks the cell's setpoints from iceoryx2 shared
/// memory at 1 kHz and publishes the measured joint state.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Cell name; the services are `prf/<cell>/setpoint`, `prf/<cell>/setpoint-ready`
    /// and `prf/<cell>/joint-state`.
    #[arg(long, default_value = "cell")]
    pub cell: String,
    /// Servo bandwidth, Hz.
    #[arg(long, default_value_t = 20.0)]
    pub bandwidth: f64,
    /// Servo damping ratio.
    #[arg(long, default_value_t = 1.0)]
    pub damping: f64,
    /// Silent cycles (1 ms each) before the watchdog brakes the arm to standstill.
    #[arg(long, default_value_t = 100)]
    pub watchdog: u32,
    /// Gripper open → closed time, s.
    #[arg(long, default_value_t = 0.6)]
    pub gripper_time: f64,
    /// Initial platform pose x,y,yaw (m, m, rad).
    #[arg(long, value_parser = parse_pose, default_value = "0,0,0", allow_hyphen_values = true)]
    pub base: [f64; 3],
    /// Log file (tracking error every 100 setpoints, sessions, faults); default
    /// `$TMPDIR/prf-firmware-sim-<cell>.log`.
    #[arg(long)]
    pub log: Option<PathBuf>,
    /// Exit when the parent process exits.
    #[arg(long)]
    pub exit_with_parent: bool,
    /// World file of the cell (or `example` or `plant`, a built-in one): the platform
    /// navigates on its floor map. Without one it drives straight lines between goals.
    #[arg(long)]
    pub world: Option<PathBuf>,
}

impl Args {
    pub fn config(&self) -> Result<Config, controller::ControllerError> {
        let mut c = Config::new(&self.cell);
        c.servo = ServoConfig {
            bandwidth_hz: self.bandwidth,
            damping: self.damping,
            ..ServoConfig::default()
        };
        c.watchdog_cycles = self.watchdog;
        c.gripper_time = self.gripper_time;
        c.base = self.base;
        if let Some(l) = &self.log {
            c.log = l.clone();
        }
        c.exit_with_parent = self.exit_with_parent;
        c.world = match &self.world {
            None => None,
            Some(p) => Some(World::named(p)?),
        };
        Ok(c)
    }
}

/// "x,y,yaw" → [x, y, yaw].
fn parse_pose(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("{x:?}: {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [x, y, yaw] if v.iter().all(|x| x.is_finite()) => Ok([x, y, yaw]),
        _ => Err(format!(
            "expected x,y,yaw (three finite numbers), got {s:?}"
        )),
    }
}

/// Runs the controller and prints its summary.
pub fn run(args: &Args) -> Result<(), controller::ControllerError> {
    let cfg = args.config()?;
    eprintln!(
        "prf firmware-sim: cell {:?}, log {}",
        cfg.cell,
        cfg.log.display()
    );
    match (&cfg.world, &args.world) {
        (Some(w), Some(p)) => eprintln!(
            "prf firmware-sim: the platform navigates on the floor map of {} ({} locations), keeping {:.0} mm",
            p.display(),
            w.locations.len(),
            w.clearance.acceptable * 1e3
        ),
        _ => eprintln!(
            "prf firmware-sim: no world file (--world): the platform drives straight lines between goals, blind to obstacles"
        ),
    }
    let s = controller::run(&cfg)?;
    eprintln!("prf firmware-sim: {s}");
    Ok(())
}
