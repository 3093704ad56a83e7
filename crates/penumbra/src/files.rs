//! Reading the files a scene names: only regular files, and never more than a bound, so that a
//! folder, a device such as `/dev/zero`, a named pipe or a huge file is refused at once
//! instead of hanging or exhausting memory.

use std::io::{self, Read};
use std::path::Path;

/// Checks that `path` is a regular file of at most `limit` bytes, before anything opens it
/// (opening a named pipe would wait for a writer). Returns its size.
pub(crate) fn check_regular(path: &Path, limit: u64) -> io::Result<u64> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        let what = if meta.is_dir() {
            "a folder"
        } else {
            "not a regular file (a device or a pipe)"
        };
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("it is {what}"),
        ));
    }
    if meta.len() > limit {
        return Err(too_large(meta.len(), limit));
    }
    Ok(meta.len())
}

/// The bytes of the regular file `path`, at most `limit` of them.
pub(crate) fn read_bounded(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let size = check_regular(path, limit)?;
    let mut bytes = Vec::new();
    bytes
        .try_reserve_exact(size as usize)
        .map_err(|_| too_large(size, limit))?;
    // Bounded even if the file grows after the check.
    std::fs::File::open(path)?
        .take(limit + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64, limit));
    }
    Ok(bytes)
}

fn too_large(size: u64, limit: u64) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!("the file is too large ({size} bytes; at most {limit})"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_devices_and_large_files_are_refused() {
        let dir = std::env::temp_dir();
        let e = read_bounded(&dir, 1 << 20).unwrap_err();
        assert!(e.to_string().contains("folder"), "{e}");
        if Path::new("/dev/zero").exists() {
            let e = read_bounded(Path::new("/dev/zero"), 1 << 20).unwrap_err();
            assert!(e.to_string().contains("not a regular file"), "{e}");
        }
        let file = dir.join(format!("penumbra-files-test-{}", std::process::id()));
        std::fs::write(&file, b"0123456789").unwrap();
        assert_eq!(read_bounded(&file, 10).unwrap(), b"0123456789");
        let e = read_bounded(&file, 9).unwrap_err();
        assert!(e.to_string().contains("too large"), "{e}");
        std::fs::remove_file(&file).unwrap();
    }
}
