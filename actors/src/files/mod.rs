//! Reading the files users name, and writing the files petrel makes, without surprises.
//!
//! Reading: only regular files (a FIFO would block a start forever, `/dev/zero` would fill
//! memory), at most a documented size per kind of file, a UTF-8 byte-order mark (as Windows
//! editors write) ignored, and a symlink loop named as such rather than "does not exist".
//! Writing: to a temporary file beside the destination, then renamed over it, so a full disk
//! or a crash never leaves a half-written snapshot or plan where a good one was.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

mod output;
pub use output::{output_problem, same_file};

/// Size limits per kind of file, in bytes. Far above any real file of the kind, low enough that
/// a wrong path (a device, a huge log) is refused before it is read.
pub mod limits {
    /// Agent configs, overlays and snapshots.
    pub const CONFIG: u64 = 64 << 20;
    /// Plans (text or PNML), execution rules and simulation scripts.
    pub const PLAN: u64 = 256 << 20;
    /// Context rules.
    pub const RULES: u64 = 16 << 20;
    /// World files and map images.
    pub const WORLD: u64 = 256 << 20;
}

/// Reads the file at `path`, a `what` ("config", "plan"...), of at most `limit` bytes. The
/// error says what is wrong with the path, without repeating it.
pub fn read_bytes(path: &Path, what: &str, limit: u64) -> Result<Vec<u8>, String> {
    let meta = regular_file(path).map_err(|e| format!("cannot read {what}: {e}"))?;
    if meta.len() > limit {
        return Err(format!(
            "cannot read {what}: it is {} bytes, above the {} limit for a {what}",
            meta.len(),
            limit
        ));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    std::fs::File::open(path)
        .and_then(|f| f.take(limit + 1).read_to_end(&mut bytes))
        .map_err(|e| format!("cannot read {what}: {}", describe(path, &e)))?;
    if bytes.len() as u64 > limit {
        return Err(format!(
            "cannot read {what}: it grew above the {limit} limit for a {what} while being read"
        ));
    }
    Ok(bytes)
}

/// The metadata of `path` if it is a regular file (links followed), else what it is instead:
/// `it does not exist`, `it is a directory`, `it is a symlink loop`, ...
pub fn regular_file(path: &Path) -> Result<std::fs::Metadata, String> {
    let meta = std::fs::metadata(path).map_err(|e| describe(path, &e))?;
    if meta.is_dir() {
        return Err("it is a directory".into());
    }
    if !meta.is_file() {
        return Err("it is not a regular file (a FIFO, device or socket)".into());
    }
    Ok(meta)
}

/// Reads a UTF-8 text file as [`read_bytes`] does, without its byte-order mark if it has one.
pub fn read_text(path: &Path, what: &str, limit: u64) -> Result<String, String> {
    let bytes = read_bytes(path, what, limit)?;
    let text = String::from_utf8(bytes).map_err(|e| {
        format!(
            "cannot read {what}: not UTF-8 text (byte {} is not valid)",
            e.utf8_error().valid_up_to()
        )
    })?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

/// `text` without a leading UTF-8 byte-order mark.
pub fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

fn describe(path: &Path, e: &std::io::Error) -> String {
    // `metadata` follows links; a loop ends in ELOOP, which std reports as an unnamed error.
    if e.raw_os_error() == Some(libc::ELOOP) {
        return "it is a symlink loop".into();
    }
    match e.kind() {
        std::io::ErrorKind::NotFound => match std::fs::symlink_metadata(path) {
            Ok(m) if m.file_type().is_symlink() => "it is a symlink to nothing".into(),
            _ => "it does not exist".into(),
        },
        std::io::ErrorKind::PermissionDenied => "permission denied".into(),
        _ => e.to_string(),
    }
}

/// Writes `contents` to `path` through a temporary file in the same directory, renamed over
/// `path` once complete and flushed: readers see the old file or the new one, never a part.
/// A symlink is written through (its target replaced); a device, FIFO, socket or folder is
/// refused, since renaming over it would replace it with a plain file.
pub fn write_atomically(path: &Path, contents: &[u8]) -> std::io::Result<()> {
    let through;
    let path = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => {
            through = std::fs::canonicalize(path)?;
            through.as_path()
        }
        _ => path,
    };
    if let Ok(meta) = std::fs::metadata(path) {
        if !meta.is_file() {
            return Err(std::io::Error::other(
                "it is not a regular file (a device, FIFO, socket or folder), which a written file would replace",
            ));
        }
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| std::io::Error::other("the destination has no file name"))?;
    let tmp = dir.join(format!(
        ".{}.{}.tmp",
        name.to_string_lossy(),
        std::process::id()
    ));
    let written = std::fs::File::create(&tmp).and_then(|mut f| {
        f.write_all(contents)?;
        f.sync_all()
    });
    match written.and_then(|()| std::fs::rename(&tmp, path)) {
        Ok(()) => Ok(()),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// Whether `output` names the same file as one of `inputs` (through links and `..` too):
/// writing it would destroy an input.
pub fn overwrites_an_input<'a>(output: &Path, inputs: &[&'a Path]) -> Option<&'a Path> {
    let out = std::fs::canonicalize(output).ok()?;
    inputs
        .iter()
        .find(|i| std::fs::canonicalize(i).is_ok_and(|i| i == out))
        .copied()
}

/// Checks, before a run, that `path` can be written later: its directory exists and accepts a
/// new file. Leaves nothing behind.
pub fn check_writable(path: &Path) -> Result<(), String> {
    if path.is_dir() {
        return Err("it is a directory".into());
    }
    let probe = path.with_file_name(format!(
        ".{}.{}.probe",
        path.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        std::process::id()
    ));
    match std::fs::File::create(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(format!("cannot write there: {}", describe(&probe, &e))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::FileTypeExt;

    #[test]
    fn only_regular_files_within_the_limit_are_read() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().to_path_buf();
        let file = dir.join("a.ron");
        std::fs::write(&file, "\u{feff}Agent()").unwrap();
        assert_eq!(read_text(&file, "config", 100).unwrap(), "Agent()");
        assert_eq!(
            read_text(&file, "config", 4).unwrap_err(),
            "cannot read config: it is 10 bytes, above the 4 limit for a config"
        );
        assert_eq!(
            read_text(&dir, "config", 100).unwrap_err(),
            "cannot read config: it is a directory"
        );
        assert_eq!(
            read_text(Path::new("/dev/zero"), "plan", 100).unwrap_err(),
            "cannot read plan: it is not a regular file (a FIFO, device or socket)"
        );
        assert_eq!(
            read_text(&dir.join("missing.ron"), "config", 100).unwrap_err(),
            "cannot read config: it does not exist"
        );
        std::fs::write(dir.join("latin1.txt"), [b'a', 0xe9]).unwrap();
        assert!(read_text(&dir.join("latin1.txt"), "rules", 100)
            .unwrap_err()
            .contains("not UTF-8 text (byte 1"));
    }

    #[test]
    fn symlink_loops_and_dangling_links_are_named() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().to_path_buf();
        let (a, b) = (dir.join("a"), dir.join("b"));
        std::os::unix::fs::symlink(&a, &b).unwrap();
        std::os::unix::fs::symlink(&b, &a).unwrap();
        assert_eq!(
            read_text(&a, "config", 100).unwrap_err(),
            "cannot read config: it is a symlink loop"
        );
        let dangling = dir.join("dangling");
        std::os::unix::fs::symlink(dir.join("nowhere"), &dangling).unwrap();
        assert_eq!(
            read_text(&dangling, "config", 100).unwrap_err(),
            "cannot read config: it is a symlink to nothing"
        );
    }

    #[test]
    fn atomic_writes_replace_whole_files_and_inputs_are_recognised() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().to_path_buf();
        let file = dir.join("snap.ron");
        write_atomically(&file, b"one").unwrap();
        write_atomically(&file, b"two").unwrap();
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "two");
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(left.len(), 1, "no temporary file left: {left:?}");

        let through = dir.join(".").join("snap.ron");
        assert_eq!(
            overwrites_an_input(&through, &[&file]),
            Some(file.as_path())
        );
        assert_eq!(overwrites_an_input(&dir.join("other.ron"), &[&file]), None);

        assert!(check_writable(&dir.join("new.ron")).is_ok());
        assert_eq!(check_writable(&dir).unwrap_err(), "it is a directory");
        assert!(check_writable(&dir.join("no/such/dir/x.ron")).is_err());
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            1,
            "the probe is gone"
        );
    }

    #[test]
    fn atomic_writes_go_through_symlinks_and_never_replace_a_device_or_fifo() {
        let tmp = tempfile::tempdir().unwrap();
        let target = tmp.path().join("target.dot");
        std::fs::write(&target, b"old").unwrap();
        let link = tmp.path().join("link.dot");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        write_atomically(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"new");

        let fifo = tmp.path().join("fifo");
        let c = std::ffi::CString::new(fifo.as_os_str().as_encoded_bytes()).unwrap();
        // SAFETY: a NUL-terminated path, a plain mode.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        assert!(write_atomically(&fifo, b"x").is_err());
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    }
}
