//! The seed corpora, made from real files: the committed blob and the example cell's tasks,
//! world, robot files and dataset, and streams of a real planned program.

use crate::fixture::{BLOB, TASKS};
use crate::joint_states;
use crate::setpoints;
use prf_files::robot::{EXAMPLE_SPHERES, EXAMPLE_URDF};
use prf_firmware_sim::controller::Input;
use prf_ipc::messages::{SetpointMsg, flags};
use prf_learn::LearnConfig;
use prf_learn::learn::Learner;
use prf_runtime::executor::Mode;
use prf_sim::world::EXAMPLE_WORLD;
use std::path::Path;

/// Setpoints of a seed stream.
const STREAM_LEN: usize = 300;

/// Every target's seeds: (target, file name, bytes). `dataset` is an example dataset's
/// directory (its manifest, first task record and the head of its first trajectory).
pub fn all(dataset: &Path) -> anyhow::Result<Vec<(&'static str, String, Vec<u8>)>> {
    let mut out = Vec::new();
    for pick in [0u8, 9] {
        let bytes = [&[pick][..], BLOB].concat();
        out.push(("blob", format!("task-{pick:02}.bin"), bytes));
    }
    for (i, t) in TASKS.iter().enumerate() {
        out.push(("task_block", format!("task-{i:02}.bin"), t.task_block()?));
    }
    let stream = arm_stream();
    let mut whole = stream.clone();
    if let Some(Input::Setpoint(m)) = whole.last_mut() {
        m.flags |= flags::LAST;
    }
    out.push((
        "setpoints",
        "arm-motion.bin".into(),
        setpoints::encode(&whole),
    ));
    let mut stalled = stream.clone();
    stalled.splice(150..150, std::iter::repeat_n(Input::Silence, 150));
    out.push((
        "setpoints",
        "watchdog.bin".into(),
        setpoints::encode(&stalled),
    ));
    let arm = joint_states::first_arm_tick();
    let with = |ticks: u64, tail: &[u8]| [joint_states::honest(ticks), tail.to_vec()].concat();
    let nan = [&[0xE0, 2][..], &f64::NAN.to_le_bytes()].concat();
    let jump = [&[0xE1, 1][..], &0.2f64.to_le_bytes()].concat();
    out.push(("joint_states", "nan.bin".into(), with(arm + 100, &nan)));
    out.push(("joint_states", "jump.bin".into(), with(arm + 300, &jump)));
    out.push((
        "joint_states",
        "stale.bin".into(),
        with(arm + 50, &[0xDF; 5]),
    ));
    out.push(("joint_states", "honest.bin".into(), with(arm + 2_000, &[])));
    let read = |name: &str| std::fs::read_to_string(dataset.join(name));
    let manifest = read("manifest.json")?;
    let csv: String = read("d000.csv")?
        .lines()
        .take(60)
        .map(|l| l.to_string() + "\n")
        .collect();
    for (kind, name, text) in [
        (0u8, "manifest.bin", manifest),
        (1, "task.bin", read("d000.task.json")?),
        (2, "trajectory.bin", csv),
    ] {
        out.push((
            "dataset",
            name.into(),
            [&[kind][..], text.as_bytes()].concat(),
        ));
    }
    out.push(("world", "example-world.json".into(), EXAMPLE_WORLD.into()));
    // The example cell's knowledge base before its first program (one program's is 1.9 MB:
    // too slow a seed; the fuzzer grows sweeps from this one).
    let model = prf_files::robot::example()?;
    let ds = prf_files::dataset::Dataset::read(dataset, &model)?;
    let mut learner = Learner::new(&ds, &model, &LearnConfig::default())?;
    let saved = learner.save()?;
    out.push(("kb", "empty.kb".into(), saved.clone()));
    // The same with an (empty) addition after the base, so that mutations reach the additions.
    let appended = [saved, learner.addition(&[]).to_vec()].concat();
    out.push(("kb", "empty-addition.kb".into(), appended));
    for (kind, name, text) in [
        (0u8, "urdf.bin", EXAMPLE_URDF),
        (1, "spheres.bin", EXAMPLE_SPHERES),
    ] {
        out.push((
            "robot",
            name.into(),
            [&[kind][..], text.as_bytes()].concat(),
        ));
    }
    Ok(out)
}

/// The first [`STREAM_LEN`] setpoints of the program's first arm motion as the cell sends
/// them: a session from q_a,H, numbered from 1.
fn arm_stream() -> Vec<Input> {
    let mut out = Vec::new();
    joint_states::honest_run(|_, sp, cell| {
        if sp.mode != Mode::Arm && out.is_empty() {
            return true;
        }
        let seq = out.len() as u64 + 1;
        let (q, qd) = cell.stage.output();
        let gripper = if sp.close_gripper {
            flags::GRIPPER_CLOSE
        } else {
            0
        };
        out.push(Input::Setpoint(SetpointMsg {
            seq,
            t_ns: seq * 1_000_000,
            q,
            qd,
            base_goal: sp.base_goal,
            mode: sp.mode as u32,
            flags: if seq == 1 { flags::FIRST } else { 0 } | gripper,
        }));
        out.len() < STREAM_LEN
    });
    out
}
