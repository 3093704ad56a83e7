//! Buffers and images: the GLB's BIN chunk, `data:` URIs (base64) and files beside the glTF
//! file, each buffer read once when an accessor first needs it, each range checked.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use gltf::buffer::Source;

use super::{GltfError, ImageSource, Result, MAX_FILE_BYTES};
use crate::files::Files;
use crate::reach::Reach;

/// The buffers of a document, read on first use.
pub(super) struct Buffers<'a> {
    blob: Option<Arc<[u8]>>,
    /// The glTF file's folder: where the files its URIs name may be (see the module
    /// `reach`).
    dir: PathBuf,
    files: &'a Files,
    read: Vec<Option<Arc<[u8]>>>,
}

impl<'a> Buffers<'a> {
    pub(super) fn new(blob: Option<Vec<u8>>, dir: &Path, files: &'a Files) -> Buffers<'a> {
        Buffers {
            blob: blob.map(Into::into),
            dir: dir.to_owned(),
            files,
            read: Vec::new(),
        }
    }

    /// The bytes of buffer `buffer` (at most its `byteLength`).
    fn buffer(&mut self, buffer: gltf::Buffer) -> Result<Arc<[u8]>> {
        let i = buffer.index();
        if let Some(Some(b)) = self.read.get(i) {
            return Ok(b.clone());
        }
        let at = format!("buffers[{i}]");
        let bytes: Arc<[u8]> = match buffer.source() {
            Source::Bin => self.blob.clone().ok_or_else(|| {
                GltfError::new(
                    &at,
                    "the buffer is the GLB's BIN chunk (it has no uri), but the file has none",
                )
            })?,
            Source::Uri(uri) => self.uri(uri, &format!("{at}.uri"), "buffer")?.into(),
        };
        let declared = buffer.length();
        if bytes.len() < declared {
            return Err(GltfError::new(
                format!("{at}.byteLength"),
                format!(
                    "the buffer declares {declared} bytes, but its data has {} (a truncated file?)",
                    bytes.len()
                ),
            ));
        }
        let bytes: Arc<[u8]> = match bytes.len() == declared {
            true => bytes,
            false => bytes[..declared].into(),
        };
        if self.read.len() <= i {
            self.read.resize(i + 1, None);
        }
        self.read[i] = Some(bytes.clone());
        Ok(bytes)
    }

    /// The buffer of `view` and the view's byte range in it, checked.
    pub(super) fn view(&mut self, view: gltf::buffer::View) -> Result<(Arc<[u8]>, Range<usize>)> {
        let buffer = self.buffer(view.buffer())?;
        let (offset, length) = (view.offset(), view.length());
        match offset
            .checked_add(length)
            .filter(|&end| end <= buffer.len())
        {
            Some(end) => Ok((buffer, offset..end)),
            None => Err(GltfError::new(
                format!("bufferViews[{}]", view.index()),
                format!(
                    "byteOffset {offset} + byteLength {length} is past the end of buffer {} \
                     ({} bytes)",
                    view.buffer().index(),
                    buffer.len()
                ),
            )),
        }
    }

    /// The bytes a `uri` (at JSON path `at`) names: a `data:` URI's, or a file's beside the
    /// glTF file.
    fn uri(&self, uri: &str, at: &str, what: &str) -> Result<Vec<u8>> {
        if let Some(data) = uri.strip_prefix("data:") {
            return data_uri(data).map_err(|e| GltfError::new(at, e));
        }
        let path = self.path(uri, at)?;
        self.files.read(&path, MAX_FILE_BYTES).map_err(|e| {
            GltfError::new(
                at,
                format!("cannot read {what} \"{}\": {e}", path.display()),
            )
        })
    }

    /// The file a relative `uri` (at `at`) names, percent-decoded, when the model may read it.
    fn path(&self, uri: &str, at: &str) -> Result<PathBuf> {
        if uri.contains("://") {
            return Err(GltfError::new(
                at,
                format!(
                    "\"{uri}\" is a remote address: only files in the glTF file's folder and \
                     below are read"
                ),
            ));
        }
        Reach::new(self.files, &self.dir, &self.dir, "model")
            .resolve(&self.dir, &percent_decode(uri))
            .map_err(|e| GltfError::new(at, e.to_string()))
    }

    /// Where the bytes of image `image` are; a file is checked to exist, not read. Read from
    /// the JSON: the `gltf` crate's `Image::source` unwraps a missing `mimeType` or `uri`
    /// (found by fuzzing), which penumbra does not need.
    pub(super) fn image(&mut self, doc: &gltf::Document, index: usize) -> Result<ImageSource> {
        let at = format!("images[{index}]");
        let json = doc
            .as_json()
            .images
            .get(index)
            .ok_or_else(|| GltfError::new(&at, "no such image"))?;
        if let Some(view) = json.buffer_view {
            let view = doc
                .views()
                .nth(view.value())
                .ok_or_else(|| GltfError::new(format!("{at}.bufferView"), "no such bufferView"))?;
            let (buffer, range) = self.view(view).map_err(|e| GltfError {
                message: format!("{} (the image's bufferView)", e.message),
                ..e
            })?;
            return Ok(ImageSource::Bytes(buffer[range].into()));
        }
        let at = format!("{at}.uri");
        let uri = json
            .uri
            .as_deref()
            .ok_or_else(|| GltfError::new(&at, "the image has neither a uri nor a bufferView"))?;
        if let Some(data) = uri.strip_prefix("data:") {
            let bytes = data_uri(data).map_err(|e| GltfError::new(&at, e))?;
            return Ok(ImageSource::Bytes(bytes.into()));
        }
        let path = self.path(uri, &at)?;
        if !self.files.is_file(&path) {
            return Err(GltfError::new(
                at,
                format!("the image file \"{}\" is missing", path.display()),
            ));
        }
        Ok(ImageSource::File(path))
    }
}

/// The bytes of a `data:` URI after `data:`: `[<media type>][;base64],<data>`.
fn data_uri(data: &str) -> std::result::Result<Vec<u8>, String> {
    let (header, payload) = data
        .split_once(',')
        .ok_or("the data URI has no ',' before its data")?;
    match header.ends_with(";base64") {
        true => base64(payload),
        false => Ok(percent_decode(payload).into_bytes()),
    }
}

/// Decodes standard base64 (padding optional, whitespace skipped).
fn base64(text: &str) -> std::result::Result<Vec<u8>, String> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    };
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    let (mut acc, mut bits) = (0u32, 0u32);
    for (i, c) in text.bytes().enumerate() {
        if c == b'=' || c.is_ascii_whitespace() {
            continue;
        }
        let v = value(c).ok_or_else(|| {
            format!(
                "the data URI's base64 has the character '{}' at {i}",
                c.escape_ascii()
            )
        })?;
        acc = (acc << 6) | v;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Ok(out)
}

/// `%XX` escapes of a URI decoded (invalid escapes kept as written).
fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok())
            .and_then(|h| u8::from_str_radix(h, 16).ok());
        match (bytes[i], hex) {
            (b'%', Some(b)) => {
                out.push(b);
                i += 3;
            }
            (b, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_decodes_with_and_without_padding() {
        assert_eq!(base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(base64("AAECAw==").unwrap(), [0, 1, 2, 3]);
        assert!(base64("a*b").unwrap_err().contains('*'));
    }

    #[test]
    fn uris_are_percent_decoded() {
        assert_eq!(percent_decode("a%20b%2"), "a b%2");
        assert_eq!(
            data_uri("application/octet-stream;base64,AAE=").unwrap(),
            [0, 1]
        );
        assert!(data_uri("nocomma").is_err());
    }
}
