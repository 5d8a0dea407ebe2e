//! Small file helpers shared by every stage that writes results: atomic writes, so that a crash or an
//! interrupted run never leaves a truncated file where a complete one is expected; and the one-line
//! error message the command-line tools print.

use std::io::Write;
use std::path::{Path, PathBuf};

/// The temporary name `path` is written under before it is renamed into place.
pub fn temporary_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(format!(".{}.tmp", std::process::id()));
    path.with_file_name(name)
}

/// Writes `bytes` to a temporary file beside `path`, flushes it to disk and renames it to `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temporary_path(path);
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// An error and its causes on one line, `outer: cause: …`, leaving out a cause whose text the line
/// already holds (this crate's errors print their `std::io::Error` source in their own message).
pub fn error_line(error: &(dyn std::error::Error + 'static)) -> String {
    let mut line = error.to_string();
    let mut cause = error.source();
    while let Some(c) = cause {
        let text = c.to_string();
        if !line.contains(&text) {
            line.push_str(": ");
            line.push_str(&text);
        }
        cause = c.source();
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_the_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("take.bvh");
        write_atomic(&path, b"first").expect("write");
        write_atomic(&path, b"second").expect("write");
        assert_eq!(std::fs::read(&path).expect("read"), b"second");
        let names: Vec<_> = std::fs::read_dir(dir.path()).expect("dir").collect();
        assert_eq!(names.len(), 1);
    }

    #[test]
    fn a_failed_write_leaves_nothing_behind() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("missing-dir").join("take.bvh");
        assert!(write_atomic(&path, b"x").is_err());
        assert!(!path.exists());
    }

    #[test]
    fn error_line_drops_a_cause_already_in_the_message() {
        let missing = || std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let bvh = crate::bvh::BvhError::Io {
            path: "clip.bvh".into(),
            source: missing(),
        };
        assert_eq!(error_line(&bvh), "clip.bvh: cannot read: no such file");
        let wrapped = anyhow::Error::new(bvh).context("training motions");
        assert_eq!(
            error_line(wrapped.as_ref()),
            "training motions: clip.bvh: cannot read: no such file"
        );
        let plain = anyhow::Error::new(missing()).context("frame 3");
        assert_eq!(error_line(plain.as_ref()), "frame 3: no such file");
    }
}
