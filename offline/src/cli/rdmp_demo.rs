//! `prf rdmp-demo`: what the math core does, on the built-in robot, in one screen.

use crate::synthetic;
use anyhow::{Context, Result};
use nalgebra::{Isometry3, Translation3, Vector3};
use prf_offline::plots::{self, LinePlot, Series};
use prf_shared::dmp::DmpParams;
use prf_shared::kinematics::ArmKinematics;
use prf_shared::nullspace::kernel;
use prf_shared::rdmp::{Rdmp, RdmpConfig, RdmpStep, integrate, null_space_coordinate};
use prf_shared::robot::RobotModel;
use prf_shared::se3::{Pose, log};
use prf_shared::{JointVector, NA};
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args, Default)]
pub struct Args {
    /// Write the demonstration, its reproduction and every generalised trajectory as CSV
    /// (t, a1..a7) into this directory, with `elbow.svg` and `elbow.png`: the elbow's x over time for all of
    /// them (the paper's Fig. 3iv).
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Duration of the demonstrated reach, s.
    #[arg(long, default_value_t = 2.5)]
    duration: f64,
}

const DEMO_DT: f64 = 0.01;

pub fn run(args: &Args) -> Result<()> {
    let duration = if args.duration > 0.0 {
        args.duration
    } else {
        2.5
    };
    let model = RobotModel::kmr_iiwa14();
    let cfg = RdmpConfig::default();
    println!(
        "PRF kinematics + RDMP demonstration — built-in KMR iiwa 14 R820 with parallel gripper"
    );
    println!(
        "robot: {NA} joints, {} collision spheres, TCP {:.3} m beyond the flange",
        model.spheres.len(),
        model.tcp.translation.vector.norm()
    );
    let home = JointVector::from(model.home);
    let k = ArmKinematics::new(&model, &home);
    println!(
        "home q_a,H = {} deg → TCP {} m (arm base frame), manipulability {:.4}",
        fmt_deg(&home),
        fmt_vec(&k.tcp.translation.vector),
        kernel(&k.jacobian(&model)).manipulability
    );

    let demo = synthetic::reach(duration, DEMO_DT);
    let mut gamma = vec![0.0; demo.len()];
    null_space_coordinate(&model, &demo, cfg.min_manipulability, &mut gamma)
        .map_err(|e| anyhow::anyhow!("null space of the demonstration: {e}"))?;
    let params = DmpParams::default();
    let rdmp = Rdmp::train(&model, &demo, &gamma, DEMO_DT, &params)
        .map_err(|e| anyhow::anyhow!("TrainRDMP: {e}"))?;
    println!(
        "\ndemonstration: {duration} s reach at {:.0} Hz ({} samples) with an elbow swivel of {} rad",
        1.0 / DEMO_DT,
        demo.len(),
        synthetic::SWIVEL
    );
    println!(
        "TrainRDMP (Alg. 1): {} bases per DMP, τ = {:.2} s, γ_g = {:.4}, max |γ| = {:.4}",
        params.n_basis,
        rdmp.duration(),
        rdmp.gamma_goal,
        gamma.iter().fold(0.0f64, |m, g| m.max(g.abs()))
    );

    let q0 = JointVector::from(demo[0]);
    let demo_goal = ArmKinematics::new(&model, &JointVector::from(*demo.last().unwrap())).tcp;
    let mut repro = Vec::new();
    integrate(&model, &rdmp, &q0, &demo_goal, &cfg, |s| repro.push(*s))
        .map_err(|e| anyhow::anyhow!("IntegrateRDMP: {e}"))?;
    let ratio = (DEMO_DT / cfg.dt).round() as usize;
    let (mut sq, mut max, mut n) = (0.0, 0.0f64, 0);
    for s in repro.iter().filter(|s| s.step % ratio == 0) {
        let d = s.q - JointVector::from(demo[s.step / ratio]);
        sq += d.norm_squared() / NA as f64;
        max = max.max(d.amax());
        n += 1;
    }
    println!(
        "IntegrateRDMP (Alg. 2) at {:.0} Hz to the demonstrated goal: joint RMSE {:.2e} rad, max {:.2e} rad",
        1.0 / cfg.dt,
        (sq / n as f64).sqrt(),
        max
    );

    println!("\ngeneralisation to new TCP goals (10 cm away, tilted 0.1 rad):");
    println!(
        "  {:>22}  {:>12}  {:>12}  {:>13}  {:>10}",
        "goal offset [m]", "end pos err", "end rot err", "max q̇/limit", "min manip."
    );
    let mut runs = Vec::new();
    for dir in [
        Vector3::x(),
        -Vector3::x(),
        Vector3::y(),
        -Vector3::y(),
        Vector3::z(),
        -Vector3::z(),
        Vector3::new(1.0, 1.0, 1.0).normalize(),
    ] {
        let goal: Pose = Isometry3::from_parts(
            Translation3::from(demo_goal.translation.vector + dir * 0.1),
            prf_shared::se3::exp(&(Vector3::new(dir.y, -dir.x, dir.z) * 0.1)) * demo_goal.rotation,
        );
        let mut traj: Vec<RdmpStep> = Vec::new();
        match integrate(&model, &rdmp, &q0, &goal, &cfg, |s| traj.push(*s)) {
            Ok(q) => {
                let end = ArmKinematics::new(&model, &q).tcp;
                let speed = traj
                    .iter()
                    .flat_map(|s| (0..NA).map(move |i| s.qd[i].abs() / model.joints[i].max_speed))
                    .fold(0.0f64, f64::max);
                let manip = traj
                    .iter()
                    .map(|s| s.manipulability)
                    .fold(f64::INFINITY, f64::min);
                println!(
                    "  {:>22}  {:>9.2e} m  {:>8.3} deg  {:>13.2}  {:>10.4}",
                    fmt_vec(&(dir * 0.1)),
                    (end.translation.vector - goal.translation.vector).norm(),
                    log(&(end.rotation * goal.rotation.inverse()))
                        .norm()
                        .to_degrees(),
                    speed,
                    manip
                );
            }
            Err(e) => println!("  {:>22}  refused: {e}", fmt_vec(&(dir * 0.1))),
        }
        runs.push((dir, traj));
    }
    println!(
        "  (speeds follow the demonstration's timing; the jerk-limited output stage keeps the arm within its limits)"
    );
    let far = Isometry3::from_parts(
        Translation3::from(demo_goal.translation.vector + Vector3::new(1.5, 0.0, 0.0)),
        demo_goal.rotation,
    );
    match integrate(&model, &rdmp, &q0, &far, &cfg, |_| {}) {
        Ok(_) => println!("\nunreachable goal 1.5 m further: integrated (unexpected)"),
        Err(e) => println!("\nunreachable goal 1.5 m further: refused with {e}"),
    }

    if let Some(dir) = &args.csv {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        write_csv(
            &dir.join("demonstration.csv"),
            demo.iter()
                .enumerate()
                .map(|(k, q)| (k as f64 * DEMO_DT, *q)),
        )?;
        write_csv(&dir.join("reproduction.csv"), steps(&repro, cfg.dt, &q0))?;
        for (i, (_, traj)) in runs.iter().enumerate() {
            write_csv(&dir.join(format!("goal{i}.csv")), steps(traj, cfg.dt, &q0))?;
        }
        let elbow_x = |q: &[f64; NA]| {
            ArmKinematics::new(&model, &JointVector::from(*q)).frames[4]
                .origin
                .x
        };
        let mut series = vec![Series {
            name: "demonstration".into(),
            points: demo
                .iter()
                .enumerate()
                .map(|(k, q)| (k as f64 * DEMO_DT, elbow_x(q)))
                .collect(),
            emphasis: true,
            colour: 0,
        }];
        for (i, (dir, traj)) in runs.iter().enumerate() {
            series.push(Series {
                name: format!("goal {}", fmt_vec(&(dir * 0.1))),
                points: steps(traj, cfg.dt, &q0)
                    .step_by(10)
                    .map(|(t, q)| (t, elbow_x(&q)))
                    .collect(),
                emphasis: false,
                colour: i,
            });
        }
        plots::save(
            &LinePlot {
                title: "RDMP generalisation: elbow (link 4) x",
                x_label: "t [s]",
                y_label: "x [m], arm base frame",
                series: &series,
            },
            &dir.join("elbow"),
        )?;
        println!(
            "trajectories and elbow.svg/.png written to {}",
            dir.display()
        );
    }
    Ok(())
}

fn steps<'a>(
    traj: &'a [RdmpStep],
    dt: f64,
    q0: &JointVector,
) -> impl Iterator<Item = (f64, [f64; NA])> + 'a {
    std::iter::once((0.0, (*q0).into()))
        .chain(traj.iter().map(move |s| (s.step as f64 * dt, s.q.into())))
}

fn write_csv(path: &std::path::Path, rows: impl Iterator<Item = (f64, [f64; NA])>) -> Result<()> {
    let mut f = std::io::BufWriter::new(
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?,
    );
    writeln!(f, "t,a1,a2,a3,a4,a5,a6,a7")?;
    for (t, q) in rows {
        write!(f, "{t:.4}")?;
        for v in q {
            write!(f, ",{v:.9}")?;
        }
        writeln!(f)?;
    }
    Ok(())
}

fn fmt_vec(v: &Vector3<f64>) -> String {
    // + 0.0 turns −0.0 into 0.0 for printing.
    format!("[{:.3}, {:.3}, {:.3}]", v.x + 0.0, v.y + 0.0, v.z + 0.0)
}

fn fmt_deg(q: &JointVector) -> String {
    let parts: Vec<String> = q.iter().map(|v| format!("{:.0}", v.to_degrees())).collect();
    format!("[{}]", parts.join(", "))
}
