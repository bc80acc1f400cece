//! Output files: frames as OBJ or PLY meshes, the run summary and the probe table. Every
//! file is written whole or not at all ([`write_atomically`]).

pub mod frames;
pub mod report;

use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes a file through `write` into a temporary file beside `path`, then renames it
/// over `path`: readers see the old file or the new one, never a part.
pub fn write_atomically(path: &Path, write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> std::io::Result<()> {
    let file_name =
        path.file_name().ok_or_else(|| std::io::Error::other(format!("{} is not a file path", path.display())))?;
    let temporary = path.with_file_name(format!(".{}.partial", file_name.to_string_lossy()));
    let result = (|| {
        let mut out = BufWriter::new(std::fs::File::create(&temporary)?);
        write(&mut out)?;
        out.into_inner().map_err(|e| e.into_error())?.sync_all()
    })();
    match result.and_then(|()| std::fs::rename(&temporary, path)) {
        Ok(()) => Ok(()),
        Err(error) => {
            let _ = std::fs::remove_file(&temporary);
            Err(error)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_partial_one() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("a.txt");
        write_atomically(&path, |w| w.write_all(b"old")).expect("first write");
        let failed = write_atomically(&path, |w| {
            w.write_all(b"new but")?;
            Err(std::io::Error::other("disk full"))
        });
        assert!(failed.is_err());
        assert_eq!(std::fs::read_to_string(&path).expect("readable"), "old");
        assert_eq!(std::fs::read_dir(dir.path()).expect("listable").count(), 1);
    }
}
