//! `prf learn`: Learn (Alg. 3) on a dataset and compile the blob.

use crate::cli::args::WorldArgs;
use crate::cli::progress::Bar;
use anyhow::Context;
use prf_files::dataset::{Dataset, DatasetDir};
use prf_files::robot;
use prf_learn::learn::{
    CHUNK, KbFile, Learner, fingerprint, learn_dir, learn_lessons_into, skills_per_class,
};
use prf_learn::{LearnConfig, compile, report};
use prf_offline::budget::{Fitted, Rung, fit};
use prf_offline::memory_map;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Dataset directory (as written by `prf gen`).
    #[arg(required_unless_present = "into")]
    pub dataset: Option<PathBuf>,
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
    #[arg(long, default_value_t = prf_learn::workspace::WorkspaceConfig::default().voxel)]
    pub voxel: f64,
    /// Bricks whose nodes are all at least this far outside Ω+ store one value, m.
    #[arg(long, default_value_t = prf_learn::workspace::WorkspaceConfig::default().far)]
    pub far: f64,
    /// Every demonstrated sphere is certified with this margin, m: a program whose spheres
    /// stay within it of where the same spheres were demonstrated rates risk 0. Larger: more
    /// part offsets plan at risk 0, a larger blob. At most ε − 0.5 mm (and at least 1 mm)
    #[arg(long, default_value_t = prf_learn::workspace::REUSE_MARGIN)]
    pub margin: f64,
    /// Also write the knowledge base (the learner's whole state) to this file, for
    /// `--add … --into`.
    #[arg(long, conflicts_with = "into")]
    pub kb: Option<PathBuf>,
    /// Fold the demonstrations of these datasets (each a directory as `prf gen` writes, of
    /// the same cell) into the knowledge base `--into`, in order, without learning the rest
    /// again: only the fields of the location types they touch are rebuilt. Writes the blob
    /// (`-o`) and appends the addition to the knowledge base (rewritten whole instead once
    /// its additions would outgrow half of it).
    #[arg(long, num_args = 1.., requires = "into", value_name = "DATASET")]
    pub add: Vec<PathBuf>,
    /// The knowledge base `--add` updates (written by `prf learn DATASET --kb FILE`).
    #[arg(
        long,
        requires = "add",
        conflicts_with_all = ["dataset", "urdf", "spheres", "clearance_demo", "clearance", "voxel", "far", "margin"]
    )]
    pub into: Option<PathBuf>,
    /// The most bytes the blob may take (default: the firmware's BLOB region in memory.x,
    /// 960 KiB; 0: no limit). A larger blob keeps only the skills that the afforded tasks of
    /// `--world` need and, if that is not enough, certifies with smaller margins (12, 8, 5, 3,
    /// 2, 1 mm) until it fits; the report says what was dropped and which tasks, if any,
    /// lost physical feasibility. `--kb` keeps everything learned.
    #[arg(long, value_name = "BYTES")]
    pub max_blob_bytes: Option<usize>,
    #[command(flatten)]
    pub world: WorldArgs,
    /// Print nothing but errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Says, on standard error, which workspaces left certificates out for want of capsule
/// indices (their spheres then rate a risk: the reuse margin is not kept everywhere).
fn uncertified_note(k: &prf_learn::Knowledge) {
    for l in &k.location_types {
        if let Some(f) = l.field.as_ref().filter(|f| f.uncertified > 0) {
            eprintln!(
                "note: workspace {} needs more than {} certificate capsules; {} certificates were left out, so some demonstrated spheres moved within the reuse margin rate a risk (learn with a smaller --margin to keep it everywhere)",
                l.name,
                prf_shared::field::MAX_CAPSULES,
                f.uncertified
            );
        }
    }
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    if let Some(kb) = &a.into {
        return add(a, kb);
    }
    let Some(dataset) = &a.dataset else {
        anyhow::bail!("no dataset given");
    };
    let t0 = Instant::now();
    let model = match (&a.urdf, &a.spheres) {
        (Some(u), Some(s)) => robot::load(u, s)?,
        _ => robot::example()?,
    };
    let dir = DatasetDir::open(dataset)?;
    let mut cfg = LearnConfig {
        clearance_demo: a.clearance_demo,
        clearance_acceptable: a.clearance,
        ..LearnConfig::default()
    };
    cfg.workspace.voxel = a.voxel;
    cfg.workspace.far = a.far;
    cfg.workspace.certify_margin = a.margin;
    let bar = Bar::new("learning", "units", a.quiet);
    let (k, mut learner) = learn_dir(&dir, &model, &cfg, CHUNK, &|p| bar.report(p))?;
    let t_learn = t0.elapsed().as_secs_f64();
    bar.finish();
    // The knowledge base keeps everything learned, whatever the blob's budget gives up.
    if let Some(kb) = &a.kb {
        prf_files::atomic::write(kb, learner.save()?)
            .with_context(|| format!("writing {}", kb.display()))?;
    }
    let timings = k
        .timings
        .iter()
        .map(|(n, t)| format!("{n} {t:.2} s"))
        .collect::<Vec<_>>()
        .join(", ");
    let t2 = Instant::now();
    let fitted = within_budget(a, &mut learner, k)?;
    let (k, bytes) = (fitted.knowledge, fitted.blob);
    let t_compile = t2.elapsed().as_secs_f64();
    prf_files::atomic::write(&a.output, &bytes)
        .with_context(|| format!("writing {}", a.output.display()))?;
    uncertified_note(&k);
    if a.quiet {
        return Ok(());
    }
    println!(
        "learned from {} demonstrations in {}: {}",
        k.demonstrations,
        dataset.display(),
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
        "time: read and learn {t_learn:.2} s ({timings}), compile (within the budget) {t_compile:.3} s"
    );
    println!("wrote {}", a.output.display());
    Ok(())
}

/// The budget `--max-blob-bytes` asks for (0: none).
fn budget(a: &Args) -> usize {
    match a
        .max_blob_bytes
        .unwrap_or_else(memory_map::blob_region_bytes)
    {
        0 => usize::MAX,
        n => n,
    }
}

/// The blob of `k` within the budget ([`prf_offline::budget::fit`]), each rung tried and
/// what was given up printed.
fn within_budget(
    a: &Args,
    learner: &mut Learner,
    k: prf_learn::Knowledge,
) -> anyhow::Result<Fitted> {
    let limit = budget(a);
    let world = a.world.load()?;
    let kib = |b: usize| b as f64 / 1024.0;
    let quiet = a.quiet;
    let bar = Bar::new("recertifying", "workspace rungs (at most)", quiet);
    let rung = |r: &Rung| {
        if !quiet {
            bar.suspend(|| {
                println!(
                    "  margins {}: {:.1} KiB with every skill, {:.1} KiB with the witnesses' only; {} tasks, {} afforded tasks physically feasible",
                    r.margins_mm(),
                    kib(r.all_skills),
                    kib(r.witnesses),
                    r.counts.physical_tasks,
                    r.counts.physical_afforded
                )
            });
        }
    };
    let (skills, rdmps) = (k.skills.len(), k.arms.len());
    let fitted = fit(learner, k, &world, limit, &|p| bar.report(p), &rung)
        .with_context(|| format!("fitting the blob within --max-blob-bytes {limit}"))?;
    bar.finish();
    if !quiet && !fitted.rungs.is_empty() {
        let f = &fitted;
        let kept = match f.knowledge.skills.len() {
            n if n == skills => "every skill".to_string(),
            n => format!(
                "{n} of {skills} skills ({} of {rdmps} RDMPs: a witness of every feasible side)",
                f.knowledge.arms.len()
            ),
        };
        println!(
            "budget {:.1} KiB: the blob of everything learned is {:.1} KiB; kept {kept}; certification margins {}",
            kib(limit),
            kib(f.unbudgeted),
            f.rungs.last().map_or_else(String::new, |r| r.margins_mm()),
        );
        let now = f.rungs.last().map(|r| r.counts).unwrap_or_default();
        println!(
            "  physically feasible: {} tasks and {} afforded tasks (unbudgeted: {} and {}); tasks lost: {}",
            now.physical_tasks,
            now.physical_afforded,
            f.reference.physical_tasks,
            f.reference.physical_afforded,
            if f.lost.is_empty() {
                "none".to_string()
            } else {
                f.lost.join(", ")
            }
        );
    }
    Ok(fitted)
}

/// `prf learn --add DATASET… --into KB`: the knowledge base, the new demonstrations folded in,
/// the blob compiled and written whole or not at all, the addition appended ([`write_kb`]).
fn add(a: &Args, kb: &std::path::Path) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let file: KbFile = Arc::new(map(kb).with_context(|| format!("reading {}", kb.display()))?);
    let bytes = (*file).as_ref();
    // The datasets are read and parsed while the knowledge base is read (its robot model
    // checks them after). The sweeps stay in the file until a rebuild reads them: only the
    // touched types' are.
    let (learner, parsed) = rayon::join(
        || Learner::open(file.clone()),
        || a.add.iter().map(|d| Dataset::parse(d)).collect::<Vec<_>>(),
    );
    let mut learner = learner.with_context(|| format!("reading {}", kb.display()))?;
    let t_load = t0.elapsed().as_secs_f64();
    let before = learner.demonstrations();
    let mut demos = Vec::new();
    for (dir, parsed) in a.add.iter().zip(parsed) {
        let ds = parsed?.check(learner.robot())?;
        learner
            .admits(&ds)
            .with_context(|| format!("adding {} to {}", dir.display(), kb.display()))?;
        demos.extend(ds.demonstrations);
    }
    let prints: Vec<u32> = demos.iter().map(fingerprint).collect();
    for (i, d) in demos.iter().enumerate() {
        if let Some(j) = prints[..i].iter().position(|p| *p == prints[i]) {
            anyhow::bail!(
                "demonstration {} is given twice (also as {}: the same task and trajectory)",
                d.id,
                demos[j].id
            );
        }
    }
    let t1 = Instant::now();
    let (k, lessons) = learn_lessons_into(&mut learner, &demos, &|_| {})
        .with_context(|| format!("learning into {}", kb.display()))?;
    let t_learn = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    // The addition is encoded while the blob is compiled, written and synced; the knowledge
    // base is appended to only once the blob is written.
    let (written, record) = rayon::join(
        || -> anyhow::Result<(Vec<u8>, f64)> {
            let blob = compile(&k)?;
            let t_compile = t2.elapsed().as_secs_f64();
            prf_files::atomic::write(&a.output, &blob)
                .with_context(|| format!("writing {}", a.output.display()))?;
            Ok((blob, t_compile))
        },
        || learner.addition(&lessons),
    );
    let (blob, t_compile) = written?;
    let kb_write = write_kb(kb, bytes, &mut learner, &record)
        .with_context(|| format!("writing {}", kb.display()))?;
    let t_write = t2.elapsed().as_secs_f64() - t_compile;
    uncertified_note(&k);
    if blob.len() > budget(a) {
        eprintln!(
            "note: the blob is {} bytes, over --max-blob-bytes {} (the firmware's BLOB region by default); an addition is not budgeted: learn the whole dataset with `prf learn DATASET --world …` to fit it",
            blob.len(),
            budget(a)
        );
    }
    if !a.quiet {
        println!(
            "added {} demonstration(s) to {} ({before} → {}): {}",
            demos.len(),
            kb.display(),
            learner.demonstrations(),
            demos
                .iter()
                .map(|d| d.id.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
        println!(
            "time: load and read {t_load:.3} s, learn {t_learn:.3} s ({}), compile {t_compile:.3} s, write {t_write:.3} s; total {:.3} s",
            k.timings
                .iter()
                .map(|(n, t)| format!("{n} {t:.3} s"))
                .collect::<Vec<_>>()
                .join(", "),
            t0.elapsed().as_secs_f64()
        );
        println!("wrote {}; {}: {kb_write}", a.output.display(), kb.display());
    }
    // The command ends the process: its decoded state (tens of MB, from many allocations)
    // is left to the exit, which releases the address space at once, instead of freed
    // block by block while the worker threads still share it (about 2.5 ms, issue 17).
    std::mem::forget((learner, k, lessons, demos, blob));
    Ok(())
}

/// The file at `path`, mapped read-only (a knowledge base is read once, in place, instead of
/// copied: the copy and its page faults were a fifth of `--add`). It is only appended to or
/// replaced by renaming while mapped, so the mapped bytes do not change.
fn map(path: &std::path::Path) -> std::io::Result<memmap2::Mmap> {
    let f = std::fs::File::open(path)?;
    // SAFETY: the mapping is private to this process and read-only; this command changes the
    // file only by appending past the mapped length or renaming a new file over it. Another
    // process truncating it meanwhile would be a concurrent `prf learn --into` on the same
    // knowledge base, which nothing supports.
    #[allow(unsafe_code)]
    unsafe {
        memmap2::Mmap::map(&f)
    }
}

/// Writes the knowledge base `kb` (read as `read`) after lessons were added: their addition
/// `record` appended, or the whole state rewritten as a new base when
/// [`prf_learn::kb::rewrite_instead`] says why. Says which.
fn write_kb(
    kb: &std::path::Path,
    read: &[u8],
    learner: &mut Learner,
    record: &prf_learn::kb::AdditionRecord,
) -> anyhow::Result<String> {
    let mb = |n: usize| n as f64 / 1e6;
    if let Some(why) = prf_learn::kb::rewrite_instead(read, record.len()) {
        let whole = learner.save()?;
        prf_files::atomic::write(kb, &whole)?;
        return Ok(format!(
            "rewritten whole ({:.1} MB): {why}",
            mb(whole.len())
        ));
    }
    prf_files::atomic::append(kb, read.len() as u64, &record.parts())?;
    let base = prf_learn::kb::base_len(read).unwrap_or(0);
    Ok(format!(
        "appended {:.2} MB (additions now {:.1} MB after a {:.1} MB base)",
        mb(record.len()),
        mb(read.len().saturating_sub(base) + record.len()),
        mb(base)
    ))
}
