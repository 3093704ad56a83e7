//! 64-bit FNV-1a (Fowler, Noll and Vo): the one hash penumbra keeps in its records, for the
//! scene's digest ([`SceneFile::digest`](crate::SceneFile::digest)) and for the files a
//! record lists ([`FileDigest`]). Fast and simple; not a cryptographic hash: it tells
//! versions of a file apart, it does not defend against forgery.

use std::io::Read;
use std::path::Path;

/// FNV-1a's 64-bit offset basis and prime.
const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// 64-bit FNV-1a over byte strings fed in order.
pub(crate) struct Fnv1a(pub(crate) u64);

impl Fnv1a {
    pub(crate) fn new() -> Fnv1a {
        Fnv1a(FNV_OFFSET)
    }

    pub(crate) fn eat(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(FNV_PRIME);
        }
    }
}

/// A file's size and the 64-bit FNV-1a of its bytes: what a record keeps of each file it
/// lists, so that `--resume` tells a whole file from one cut short or changed since.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FileDigest {
    /// The file's length in bytes.
    pub bytes: u64,
    /// FNV-1a (64-bit) of its bytes.
    pub fnv1a: u64,
}

impl FileDigest {
    /// The digest of `bytes`.
    ///
    /// ```
    /// let d = penumbra::FileDigest::of_bytes(b"a");
    /// assert_eq!((d.bytes, d.hex()), (1, "af63dc4c8601ec8c".to_owned()));
    /// ```
    pub fn of_bytes(bytes: &[u8]) -> FileDigest {
        let mut hash = Fnv1a::new();
        hash.eat(bytes);
        FileDigest {
            bytes: bytes.len() as u64,
            fnv1a: hash.0,
        }
    }

    /// The digest of the regular file at `path` (read in pieces; a folder, a named pipe or
    /// a device is an error, never read).
    pub fn of_file(path: &Path) -> std::io::Result<FileDigest> {
        if !std::fs::metadata(path)?.is_file() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "not a regular file",
            ));
        }
        let mut file = std::fs::File::open(path)?;
        let (mut hash, mut bytes) = (Fnv1a::new(), 0u64);
        let mut buffer = vec![0u8; 1 << 16];
        loop {
            let n = file.read(&mut buffer)?;
            if n == 0 {
                break;
            }
            hash.eat(&buffer[..n]);
            bytes += n as u64;
        }
        Ok(FileDigest {
            bytes,
            fnv1a: hash.0,
        })
    }

    /// The hash as 16 hex digits, as records write it.
    pub fn hex(&self) -> String {
        format!("{:016x}", self.fnv1a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_matches_the_published_vectors() {
        // From the FNV reference's test suite.
        assert_eq!(FileDigest::of_bytes(b"").fnv1a, 0xcbf29ce484222325);
        assert_eq!(FileDigest::of_bytes(b"foobar").fnv1a, 0x85944171f73967e8);
        let dir = std::env::temp_dir().join(format!("penumbra-fnv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let big: Vec<u8> = (0..200_000u32).map(|i| (i * 7 % 251) as u8).collect();
        std::fs::write(dir.join("f"), &big).unwrap();
        assert_eq!(
            FileDigest::of_file(&dir.join("f")).unwrap(),
            FileDigest::of_bytes(&big)
        );
        assert!(FileDigest::of_file(&dir).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
