//! The knowledge-base file (issue 17, `prf learn --add … --into KB`): learning demonstrations
//! into a saved learner gives the blob batch learning gives, byte for byte (library and the
//! real binary), and bad files and unfit datasets are refused with a reason.

mod common;

use common::TempDir;
use prf_files::dataset::{Dataset, DatasetDir, ErrorKind};
use prf_learn::kb::{HEADER, KbError};
use prf_learn::learn::{
    LearnError, Learner, fingerprint, learn_dir, learn_into, learn_lessons_into,
};
use prf_learn::{LearnConfig, compile, learn};
use prf_shared::robot::RobotModel;
use prf_sim::demogen::generate_dataset;
use prf_sim::world::World;
use std::process::Command;
use std::sync::{Arc, OnceLock};

/// Afforded tasks of the example cell: CNC, Printer and Table types, both parts.
const SELECTION: [usize; 5] = [0, 8, 54, 13, 60];

/// The demonstrations (generated once per test binary).
fn dataset() -> &'static Dataset {
    static DS: OnceLock<Dataset> = OnceLock::new();
    DS.get_or_init(|| {
        let world = World::example();
        let all = world.afforded_tasks();
        let selection: Vec<_> = SELECTION.iter().map(|&i| all[i]).collect();
        generate_dataset(&world, &selection, 1, 100.0, &|_| {}).expect("dataset")
    })
}

/// `ds` with only the demonstrations in `range`.
fn part(ds: &Dataset, range: std::ops::Range<usize>) -> Dataset {
    let mut d = ds.clone();
    d.demonstrations = ds.demonstrations[range].to_vec();
    d
}

#[test]
fn a_saved_learner_adds_demonstrations_as_batch_learning_does() {
    let ds = dataset();
    let model = RobotModel::kmr_iiwa14();
    let cfg = LearnConfig::default();
    let batch = compile(&learn(ds, &model, &cfg, &|_| {}).unwrap()).unwrap();
    let mut first = Learner::new(ds, &model, &cfg).unwrap();
    let k3 = learn_into(&mut first, &ds.demonstrations[..3], &|_| {}).unwrap();
    let saved = first.save().unwrap();
    let mut loaded = Learner::load(&saved).expect("load");
    assert!(
        loaded.save().unwrap() == saved,
        "save → load → save is the same file"
    );
    assert_eq!(
        compile(&loaded.knowledge(&|_| {}).unwrap()).unwrap(),
        compile(&k3).unwrap(),
        "the loaded learner knows what the saved one knew"
    );
    // Opened with its sweeps left in the file: the same file saved, the same blobs.
    let mut opened = Learner::open(Arc::new(saved.clone())).expect("open");
    assert!(opened.save().unwrap() == saved, "save → open → save");
    let k5 = learn_into(&mut opened, &ds.demonstrations[3..], &|_| {}).unwrap();
    assert!(
        compile(&k5).unwrap() == batch,
        "3 demonstrations saved, opened, then 2 added: the batch blob"
    );
    let k5 = learn_into(&mut loaded, &ds.demonstrations[3..], &|_| {}).unwrap();
    assert!(
        compile(&k5).unwrap() == batch,
        "3 demonstrations saved, loaded, then 2 added: the batch blob"
    );
    assert!(opened.save().unwrap() == loaded.save().unwrap());
    assert_eq!(loaded.demonstrations(), 5);
    let ids: Vec<&str> = loaded.ids().iter().map(|(id, _)| id.as_str()).collect();
    let expected: Vec<&str> = ds.demonstrations.iter().map(|d| d.id.as_str()).collect();
    assert_eq!(ids, expected);
}

/// Learning a dataset directory a chunk at a time (what `prf learn DATASET` does, holding
/// one chunk's programs) gives batch learning's blob and knowledge base byte for byte, for
/// every chunk size; a fault in a later chunk is reported with its file and line.
#[test]
fn learning_in_chunks_gives_the_batch_blob_and_knowledge_base() {
    let model = RobotModel::kmr_iiwa14();
    let cfg = LearnConfig::default();
    let tmp = TempDir::new("chunks");
    let dir = tmp.path().join("dataset");
    dataset().write(&dir).unwrap();
    // The reference learns the dataset as read back (the files keep 9 decimals).
    let ds = Dataset::read(&dir, &model).unwrap();
    let mut batch = Learner::new(&ds, &model, &cfg).unwrap();
    let blob = compile(&learn_into(&mut batch, &ds.demonstrations, &|_| {}).unwrap()).unwrap();
    let kb = batch.save().unwrap();
    let opened = DatasetDir::open(&dir).unwrap();
    assert_eq!(opened.len(), ds.demonstrations.len());
    for chunk in [1, 2, 5, 32] {
        let (k, mut learner) = learn_dir(&opened, &model, &cfg, chunk, &|_| {}).unwrap();
        assert!(
            compile(&k).unwrap() == blob,
            "chunks of {chunk}: the batch blob"
        );
        assert!(
            learner.save().unwrap() == kb,
            "chunks of {chunk}: the batch knowledge base"
        );
    }
    // A trajectory of the last chunk with a letter for a joint angle, on line 40.
    let csv = dir.join("d004.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut fields: Vec<String> = lines[39].split(',').map(str::to_string).collect();
    fields[5] = "x".into();
    lines[39] = fields.join(",");
    std::fs::write(&csv, lines.join("\n") + "\n").unwrap();
    let Err(LearnError::Dataset(e)) = learn_dir(&opened, &model, &cfg, 2, &|_| {}) else {
        panic!("a bad number in the last chunk is refused");
    };
    assert_eq!((e.file.as_path(), e.line), (csv.as_path(), Some(40)));
    assert!(matches!(e.kind, ErrorKind::BadNumber { .. }), "{e}");
}

/// `prf learn --add` appends an addition instead of rewriting the file: a knowledge base with
/// additions loads as the learner that appended them (the same state, saved), and learns on
/// to the batch blob; an addition cut short or corrupted is refused, naming where it starts.
#[test]
fn appended_additions_load_as_the_learner_that_appended_them() {
    let ds = dataset();
    let model = RobotModel::kmr_iiwa14();
    let cfg = LearnConfig::default();
    let batch = compile(&learn(ds, &model, &cfg, &|_| {}).unwrap()).unwrap();
    let mut first = Learner::new(ds, &model, &cfg).unwrap();
    learn_into(&mut first, &ds.demonstrations[..2], &|_| {}).unwrap();
    let mut file = first.save().unwrap();
    let mut starts = Vec::new();
    for range in [2..3, 3..5] {
        // As `prf learn --add` does: the sweeps read only for the types rebuilt.
        let mut writer = Learner::open(Arc::new(file.clone())).expect("open");
        let (k, lessons) =
            learn_lessons_into(&mut writer, &ds.demonstrations[range], &|_| {}).expect("learn");
        starts.push(file.len());
        file.extend(writer.addition(&lessons).to_vec());
        let written = writer.save().unwrap();
        let mut reader = Learner::load(&file).expect("load with additions");
        assert!(
            reader.save().unwrap() == written,
            "the learner loaded is the learner that appended"
        );
        assert!(compile(&reader.knowledge(&|_| {}).unwrap()).unwrap() == compile(&k).unwrap());
        // Opened, the additions' rebuilds are kept until a sweep is read: saving reads them.
        let mut opened = Learner::open(Arc::new(file.clone())).expect("open with additions");
        assert!(
            opened.save().unwrap() == written,
            "the learner opened is the learner that appended"
        );
    }
    // The additions' rebuilds kept until the next build reads the sweeps.
    let mut all = Learner::open(Arc::new(file.clone())).unwrap();
    assert!(
        compile(&all.knowledge(&|_| {}).unwrap()).unwrap() == batch,
        "2 learned, then 1 and 2 appended: the batch blob"
    );
    let mut all = Learner::load(&file).unwrap();
    assert!(
        compile(&all.knowledge(&|_| {}).unwrap()).unwrap() == batch,
        "2 learned, then 1 and 2 appended: the batch blob"
    );
    assert_eq!(all.demonstrations(), 5);

    // Additions go after the base while they stay within half of it.
    use prf_learn::kb::rewrite_instead;
    let base = first.save().unwrap();
    assert_eq!(rewrite_instead(&base, base.len() / 2), None);
    let over = rewrite_instead(&base, base.len() / 2 + 1).unwrap_or_default();
    assert!(over.contains("over half"), "{over}");

    let load = |b: &[u8]| Learner::load(b).map(|_| ()).unwrap_err();
    let e = load(&file[..file.len() - 1]);
    assert!(
        matches!(e, KbError::CutAddition { n: 2, at, .. } if at == starts[1]),
        "{e}"
    );
    assert!(
        Learner::load(&file[..starts[1]]).is_ok(),
        "the bytes before a cut-short addition are the knowledge base before it"
    );
    assert!(matches!(
        load(&file[..starts[0] + 5]),
        KbError::CutAddition { n: 1, .. }
    ));
    let mut flipped = file.clone();
    flipped[starts[1] + 100] ^= 0x20;
    let e = load(&flipped);
    assert!(
        matches!(&e, KbError::Addition { n: 2, at, .. } if *at == starts[1]),
        "{e}"
    );
}

/// A learner of the dataset's first two demonstrations.
fn first_two() -> Learner {
    let ds = dataset();
    let model = RobotModel::kmr_iiwa14();
    let mut l = Learner::new(ds, &model, &LearnConfig::default()).unwrap();
    learn_into(&mut l, &ds.demonstrations[..2], &|_| {}).unwrap();
    l
}

/// The byte ranges of the base's sweep sections (header included), read from the layout
/// `docs/formats.md` states: the core's length at bytes 18..26, then per location type a
/// section's payload length (u64 LE) and CRC-32 before its payload.
fn sections(file: &[u8], types: usize) -> Vec<std::ops::Range<usize>> {
    let u64_at = |i: usize| u64::from_le_bytes(file[i..i + 8].try_into().unwrap()) as usize;
    let mut at = HEADER + u64_at(18);
    (0..types)
        .map(|_| {
            let range = at..at + 12 + u64_at(at);
            at = range.end;
            range
        })
        .collect()
}

/// `Learner::open` reads a location type's sweep only when a build needs it: a corrupt sweep
/// section refuses `Learner::load` and, opened, only the programs that grow that type, naming
/// it; other programs learn the blob the intact file learns, and the corrupt section is saved
/// as it was, not mended or dropped.
#[test]
fn a_sweep_is_read_only_when_its_type_is_rebuilt() {
    let ds = dataset();
    let mut l = first_two();
    let file = l.save().unwrap();
    let names = prf_learn::learn::location_kinds(ds);
    let swept: Vec<Vec<usize>> = ds.demonstrations[2..]
        .iter()
        .map(|d| l.lessons(d).unwrap().swept_types())
        .collect();
    let (mut refused, mut learned) = (0, 0);
    for (t, range) in sections(&file, names.len()).into_iter().enumerate() {
        let mut corrupt = file.clone();
        corrupt[(range.start + 12 + range.end) / 2] ^= 0x08;
        let e = Learner::load(&corrupt).map(|_| ()).unwrap_err();
        assert!(
            matches!(&e, KbError::Sweep { location_type, at, .. } if *location_type == names[t] && *at == range.start),
            "{e}"
        );
        assert!(e.to_string().contains("is corrupt: CRC-32"), "{e}");
        for (i, types) in swept.iter().enumerate() {
            let d = &ds.demonstrations[2 + i..3 + i];
            let mut opened = Learner::open(Arc::new(corrupt.clone())).expect("opened");
            let k = learn_into(&mut opened, d, &|_| {});
            if types.contains(&t) {
                let e = k.map(|_| ()).unwrap_err();
                assert!(
                    matches!(&e, LearnError::Kb(KbError::Sweep { location_type, .. }) if *location_type == names[t]),
                    "{e}"
                );
                refused += 1;
                continue;
            }
            let mut intact = Learner::load(&file).unwrap();
            let expected = compile(&learn_into(&mut intact, d, &|_| {}).unwrap()).unwrap();
            assert!(compile(&k.unwrap()).unwrap() == expected, "{}", d[0].id);
            let saved = opened.save().unwrap();
            let e = Learner::load(&saved).map(|_| ()).unwrap_err();
            assert!(
                matches!(&e, KbError::Sweep { location_type, .. } if *location_type == names[t]),
                "{e}"
            );
            assert_eq!(saved.len(), intact.save().unwrap().len());
            learned += 1;
        }
    }
    assert!(
        refused >= names.len() && learned > 0,
        "{refused} refused, {learned} learned"
    );
}

/// A program's fingerprint is the blob's CRC-32 (`prf_shared::blob::crc32`, table-driven) of
/// its task — the part, the from and the to location, each its id and type (a u32 LE length,
/// then the bytes) and pose, then the goal — and every sample's t, gripper, base and arm
/// values, the numbers in little-endian f64, in order; neither the id nor the note counts.
#[test]
fn a_fingerprint_is_the_crc_of_the_task_and_trajectory() {
    for d in &dataset().demonstrations {
        let mut bytes = Vec::new();
        for p in [&d.task.part, &d.task.from, &d.task.to] {
            for text in [&p.id, &p.kind] {
                bytes.extend((text.len() as u32).to_le_bytes());
                bytes.extend(text.as_bytes());
            }
            bytes.extend(p.pose.iter().flat_map(|v| v.to_le_bytes()));
        }
        bytes.extend(d.task.goal.iter().flat_map(|v| v.to_le_bytes()));
        bytes.extend(
            d.samples
                .iter()
                .flat_map(|s| [s.t, s.gripper].into_iter().chain(s.base).chain(s.arm))
                .flat_map(f64::to_le_bytes),
        );
        assert_eq!(fingerprint(d), prf_shared::blob::crc32(&bytes), "{}", d.id);
        let mut renamed = d.clone();
        renamed.id = "d999".into();
        renamed.task.note = Some("the same program again".into());
        assert_eq!(fingerprint(&renamed), fingerprint(d), "{}", d.id);
    }
}

#[test]
fn unfit_datasets_and_bad_files_are_refused_with_a_reason() {
    let ds = dataset();
    let model = RobotModel::kmr_iiwa14();
    let mut l = first_two();
    // The same program again, under any id.
    let mut again = part(ds, 1..2);
    again.demonstrations[0].id = "d999".into();
    let e = l.admits(&again).unwrap_err();
    assert!(
        matches!(&e, LearnError::AlreadyAdded { id, as_id } if id == "d999" && as_id == "d001"),
        "{e}"
    );
    // The same trajectory for the other part is another program (prf gen's Part1 and Part2
    // programs between the same locations move alike): it teaches that part's grasp.
    let mut other_part = again.clone();
    let task = &mut other_part.demonstrations[0].task;
    let other = ds.parts.iter().find(|p| p.id != task.part.id).unwrap();
    (task.part.id, task.part.kind) = (other.id.clone(), other.kind.clone());
    assert!(l.admits(&other_part).is_ok());
    // Programs that kept less clearance than the workspaces were dilated for.
    let mut closer = part(ds, 2..3);
    closer.clearance_demo = Some(0.04);
    let e = l.admits(&closer).unwrap_err();
    assert!(matches!(e, LearnError::ClearanceBelowKb { .. }), "{e}");
    closer.clearance_demo = None;
    assert!(matches!(l.admits(&closer), Err(LearnError::NoClearance)));
    // Another cell.
    let mut other = part(ds, 2..3);
    other.locations[0].kind = "Lathe".into();
    let e = l.admits(&other).unwrap_err();
    assert!(matches!(e, LearnError::OtherCell { .. }), "{e}");
    assert!(l.admits(&part(ds, 2..5)).is_ok());

    // Settings that would size a grid beyond memory (the fuzzer's first find: ε = 1e300
    // overflowed the grid size) are refused when the file is read.
    let mut huge = part(ds, 0..1);
    huge.clearance_demo = Some(1e300);
    let mut wide = Learner::new(&huge, &model, &LearnConfig::default()).unwrap();
    let e = Learner::load(&wide.save().unwrap())
        .map(|_| ())
        .unwrap_err();
    assert_eq!(
        e,
        KbError::Decode("a workspace setting out of range".into())
    );

    // A robot sphere of 1e300 m with swept spheres queued (the fuzzer's second find: the next
    // field build's grid size overflowed) is refused when the file is read.
    let mut giant = model.clone();
    giant.spheres[0].radius = 1e300;
    let mut queued = Learner::new(ds, &giant, &LearnConfig::default()).unwrap();
    queued.add(&queued.lessons(&ds.demonstrations[0]).unwrap());
    let e = Learner::load(&queued.save().unwrap())
        .map(|_| ())
        .unwrap_err();
    assert_eq!(
        e,
        KbError::Decode("a robot sphere's radius out of range".into())
    );

    let good = l.save().unwrap();
    let load = |b: &[u8]| Learner::load(b).map(|_| ()).unwrap_err();
    assert_eq!(load(b"not a knowledge base at all"), KbError::Magic);
    for found in [3, 9] {
        let mut v = good.clone();
        v[6] = found as u8;
        let e = load(&v);
        assert_eq!(e, KbError::Version { found });
        assert!(e.to_string().contains("learn it again"), "{e}");
    }
    assert!(matches!(
        load(&good[..good.len() - 1]),
        KbError::Truncated { .. }
    ));
    let mut flipped = good.clone();
    flipped[HEADER + 3] ^= 0x20;
    assert!(matches!(load(&flipped), KbError::Crc { .. }));
    // A core with a valid checksum that is not a learner.
    let junk = vec![0xffu8; 64];
    let mut forged = good[..HEADER].to_vec();
    forged[10..18].copy_from_slice(&(junk.len() as u64).to_le_bytes());
    forged[18..26].copy_from_slice(&(junk.len() as u64).to_le_bytes());
    let crc = prf_shared::blob::crc32(&junk);
    forged[26..30].copy_from_slice(&crc.to_le_bytes());
    forged.extend_from_slice(&junk);
    assert!(matches!(load(&forged), KbError::Decode(_)));
}

/// The real binary: `prf learn A --kb KB`, then `prf learn --add B --into KB` and `--add C`
/// give the blob of `prf learn A+B+C`; adding B again is refused and leaves the knowledge base
/// as it was.
#[test]
fn prf_learn_add_into_a_knowledge_base_gives_the_batch_blob() {
    let ds = dataset();
    let tmp = TempDir::new("kb");
    let dir = |n: &str| tmp.path().join(n);
    part(ds, 0..2).write(&dir("a")).unwrap();
    part(ds, 2..4).write(&dir("b")).unwrap();
    part(ds, 4..5).write(&dir("c")).unwrap();
    ds.write(&dir("all")).unwrap();
    let prf = |args: &[&std::ffi::OsStr]| {
        Command::new(env!("CARGO_BIN_EXE_prf"))
            .args(args)
            .output()
            .unwrap()
    };
    let os = |p: &std::path::Path| p.as_os_str().to_owned();
    let ok = |out: std::process::Output| {
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let (kb, blob, all) = (dir("kb.bin"), dir("ab.blob"), dir("all.blob"));
    ok(prf(&[
        "learn".as_ref(),
        &os(&dir("a")),
        "--kb".as_ref(),
        &os(&kb),
        "-o".as_ref(),
        &os(&dir("a.blob")),
        "-q".as_ref(),
    ]));
    let add = |what: &str| {
        prf(&[
            "learn".as_ref(),
            "--add".as_ref(),
            &os(&dir(what)),
            "--into".as_ref(),
            &os(&kb),
            "-o".as_ref(),
            &os(&blob),
        ])
    };
    // B's addition of two programs would outgrow half the base of 2 (the file is rewritten
    // whole), C's of one fits beside the base of 4 (it is appended): both ways are taken.
    for (what, added, written) in [("b", 2, "rewritten whole"), ("c", 1, "appended")] {
        let said = ok(add(what));
        println!("{said}");
        assert!(
            said.contains(&format!("added {added} demonstration(s)")),
            "{said}"
        );
        assert!(said.contains(written), "{said}");
    }
    ok(prf(&[
        "learn".as_ref(),
        &os(&dir("all")),
        "-o".as_ref(),
        &os(&all),
        "-q".as_ref(),
    ]));
    assert!(
        std::fs::read(&blob).unwrap() == std::fs::read(&all).unwrap(),
        "the batch blob"
    );
    let before = std::fs::read(&kb).unwrap();
    let again = add("b");
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(!again.status.success());
    assert!(err.contains("already in the knowledge base"), "{err}");
    assert!(
        std::fs::read(&kb).unwrap() == before,
        "the knowledge base is unchanged"
    );
}
