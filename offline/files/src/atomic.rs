//! Files and directories written whole or not at all (issue 18): everything is written to a
//! temporary file (or directory) beside the target, synced, and then renamed over it — a
//! directory by exchanging the two atomically (`renameat2(RENAME_EXCHANGE)`). A full disk, a
//! file-size limit or a killed process leaves the previous version intact; at worst a
//! temporary `.prf-tmp-*` entry stays beside it. An append-only file grows by [`append`].
//! A target that is a device, pipe or socket (`-o /dev/null`, a FIFO) is written into as it
//! is: a file renamed over it would replace the node itself.

use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// Prefix of the temporary entries.
pub const TMP_PREFIX: &str = ".prf-tmp-";

fn parent(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// The directory the temporary entry for `path` goes in, created if missing (like the target's
/// own parent directories: `prf gen -o new/dir/dataset` works on a fresh checkout).
fn parent_created(path: &Path) -> io::Result<&Path> {
    let p = parent(path);
    std::fs::create_dir_all(p)?;
    Ok(p)
}

/// Whether `path` is a device, pipe or socket: neither a regular file nor a directory.
fn special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// A temporary file beside `path`, with `path`'s extension (some writers choose the format by
/// it); in the system's temporary directory when `path` is a device, pipe or socket (beside
/// `/dev/null` is `/dev`).
pub fn temp_beside(path: &Path) -> io::Result<tempfile::NamedTempFile> {
    let suffix = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let dir = if special(path) {
        std::env::temp_dir()
    } else {
        parent_created(path)?.to_path_buf()
    };
    tempfile::Builder::new()
        .prefix(TMP_PREFIX)
        .suffix(&suffix)
        .tempfile_in(dir)
}

/// Moves a complete temporary file over `path` (after syncing it); into `path` when it is a
/// device, pipe or socket, whose node stays.
pub fn persist(tmp: tempfile::NamedTempFile, path: &Path) -> io::Result<()> {
    if special(path) {
        let mut out = std::fs::OpenOptions::new().write(true).open(path)?;
        io::copy(&mut tmp.reopen()?, &mut out)?;
        return Ok(());
    }
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// Writes `bytes` to `path` whole or not at all.
pub fn write(path: &Path, bytes: impl AsRef<[u8]>) -> io::Result<()> {
    let mut tmp = temp_beside(path)?;
    tmp.write_all(bytes.as_ref())?;
    persist(tmp, path)
}

/// Appends `parts`, in order, to the file at `path`, which must still be `len` bytes long (as
/// read), and syncs it. A failed write is undone by cutting the file back to `len` bytes; a
/// process killed mid-append leaves a cut-short tail, which a reader of an append-only format
/// (a knowledge base's additions) detects by its length and CRC and reports.
pub fn append(path: &Path, len: u64, parts: &[&[u8]]) -> io::Result<()> {
    let mut f = std::fs::OpenOptions::new().append(true).open(path)?;
    let now = f.metadata()?.len();
    if now != len {
        return Err(io::Error::other(format!(
            "{} is {now} bytes, not the {len} read: changed while this command ran",
            path.display()
        )));
    }
    let written = parts
        .iter()
        .try_for_each(|b| f.write_all(b))
        .and_then(|()| f.sync_data());
    if written.is_err() {
        // Best effort: the error reported is the write's.
        let _ = f.set_len(len).and_then(|()| f.sync_data());
    }
    written
}

/// A file written by `fill` through a handle, placed at `path` only if `fill` succeeds.
pub fn write_with<T>(path: &Path, fill: impl FnOnce(&mut File) -> io::Result<T>) -> io::Result<T> {
    let mut tmp = temp_beside(path)?;
    let out = fill(tmp.as_file_mut())?;
    persist(tmp, path)?;
    Ok(out)
}

/// Fills a new directory with `fill` and puts it in place of `dir` (created if missing) by an
/// atomic exchange; the previous contents are then removed.
pub fn replace_dir<T>(dir: &Path, fill: impl FnOnce(&Path) -> io::Result<T>) -> io::Result<T> {
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "dir".into());
    let tmp = tempfile::Builder::new()
        .prefix(&format!("{TMP_PREFIX}{name}-"))
        .tempdir_in(parent_created(dir)?)?;
    let out = fill(tmp.path())?;
    for entry in std::fs::read_dir(tmp.path())? {
        File::open(entry?.path())?.sync_all()?;
    }
    let staged: PathBuf = tmp.keep();
    if dir.exists() {
        rustix::fs::renameat_with(
            rustix::fs::CWD,
            &staged,
            rustix::fs::CWD,
            dir,
            rustix::fs::RenameFlags::EXCHANGE,
        )?;
        // `staged` now holds the previous contents.
        std::fs::remove_dir_all(&staged)?;
    } else {
        std::fs::rename(&staged, dir)?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_and_directories_are_replaced_whole_and_failures_leave_the_old_version() {
        let base = tempfile::tempdir().unwrap();
        let f = base.path().join("a.bin");
        write(&f, b"old").unwrap();
        write(&f, b"new").unwrap();
        assert_eq!(std::fs::read(&f).unwrap(), b"new");
        let failed = write_with(&f, |file| {
            file.write_all(b"partial")?;
            Err::<(), _>(io::Error::other("disk full"))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read(&f).unwrap(), b"new");

        let d = base.path().join("ds");
        replace_dir(&d, |t| std::fs::write(t.join("x"), "1")).unwrap();
        replace_dir(&d, |t| std::fs::write(t.join("y"), "2")).unwrap();
        assert!(!d.join("x").exists() && d.join("y").exists());
        let failed = replace_dir(&d, |t| {
            std::fs::write(t.join("z"), "3")?;
            Err::<(), _>(io::Error::other("killed"))
        });
        assert!(failed.is_err());
        assert!(d.join("y").exists() && !d.join("z").exists());
        // Nothing temporary is left behind after success or a failure that returns.
        let names: Vec<String> = std::fs::read_dir(base.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
    }

    /// `-o /dev/null` or a FIFO: the bytes go into the node, which stays what it was (a file
    /// renamed over `/dev/null` had replaced the device for every process on the machine).
    #[test]
    fn a_pipe_is_written_into_not_replaced() {
        use std::io::Read;
        use std::os::unix::fs::FileTypeExt;
        let base = tempfile::tempdir().unwrap();
        let fifo = base.path().join("out.blob");
        rustix::fs::mknodat(
            rustix::fs::CWD,
            &fifo,
            rustix::fs::FileType::Fifo,
            rustix::fs::Mode::from_raw_mode(0o600),
            0,
        )
        .unwrap();
        for bytes in [&b"first"[..], &b"second"[..]] {
            let reader = {
                let fifo = fifo.clone();
                std::thread::spawn(move || {
                    let mut got = Vec::new();
                    File::open(fifo).unwrap().read_to_end(&mut got).unwrap();
                    got
                })
            };
            write(&fifo, bytes).unwrap();
            // Before the join: a reader of a replaced node would wait for ever.
            assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
            assert_eq!(reader.join().unwrap(), bytes);
        }
        // Nothing temporary was left beside it.
        assert_eq!(std::fs::read_dir(base.path()).unwrap().count(), 1);
    }

    #[test]
    fn missing_parent_directories_are_created() {
        let base = tempfile::tempdir().unwrap();
        let f = base.path().join("a/b/cell.blob");
        write(&f, b"blob").unwrap();
        assert_eq!(std::fs::read(&f).unwrap(), b"blob");
        let d = base.path().join("c/d/dataset");
        replace_dir(&d, |t| std::fs::write(t.join("x"), "1")).unwrap();
        assert!(d.join("x").exists());
    }
}
