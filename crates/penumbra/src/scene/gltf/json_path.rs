//! The JSON path of a `serde_json` error: the `gltf` crate deserializes the whole document with
//! `serde_json`, whose errors give a line and column ("missing field `type` at line 1 column
//! 288"); penumbra's messages give the JSON path instead (`accessors[0].type`). The path is
//! found by scanning the JSON's tokens up to the error's position and keeping the stack of
//! open objects (with their current key) and arrays (with their current index).

use super::GltfError;

/// One open container at the error's position.
enum Frame {
    /// An object, with its current key; `in_value` once that key's `:` has been read.
    Object { key: Option<String>, in_value: bool },
    /// An array and the index of its current element.
    Array(usize),
}

/// The error of a JSON document `json` that `serde_json` could not read as glTF: at the JSON
/// path of the value at fault for a data error (a missing key names the key, as
/// `accessors[0].type`), at the line and column for a syntax error (where there is no value
/// yet).
pub(super) fn located(json: &[u8], e: &serde_json::Error) -> GltfError {
    let text = e.to_string();
    // serde_json appends " at line L column C" to every positioned message.
    let message = match text.rfind(" at line ") {
        Some(i) if e.line() > 0 => &text[..i],
        _ => &text[..],
    };
    if !e.is_data() {
        return GltfError::new("", format!("the JSON cannot be read: {text}"));
    }
    // serde_json's position is just past the closing brace of an object that lacks a key,
    // and one past the first byte of a value of the wrong type.
    let offset = offset_of(json, e.line(), e.column());
    let before = offset.checked_sub(1).map(|i| json[i]);
    match missing_key(message) {
        Some(key) => {
            // Up to the closing brace: the object that lacks `key` is the innermost one open.
            let end = offset - usize::from(before == Some(b'}'));
            let mut frames = frames_at(json, end);
            if let Some(Frame::Object { .. }) = frames.last() {
                frames.pop();
            }
            let at = join(&path(&frames), key);
            GltfError::new(at, format!("the required key `{key}` is missing"))
        }
        None => {
            // An object or array of the wrong type is not yet open.
            let end = offset - usize::from(matches!(before, Some(b'{' | b'[')));
            GltfError::new(path(&frames_at(json, end)), message)
        }
    }
}

/// The key a "missing field `key`" message names.
fn missing_key(message: &str) -> Option<&str> {
    message.strip_prefix("missing field `")?.strip_suffix('`')
}

/// The byte offset of `serde_json`'s 1-based `line` and byte `column` in `json` (clamped to
/// its length).
fn offset_of(json: &[u8], line: usize, column: usize) -> usize {
    let start = match line {
        0 | 1 => 0,
        n => json
            .iter()
            .enumerate()
            .filter(|(_, &b)| b == b'\n')
            .nth(n - 2)
            .map_or(json.len(), |(i, _)| i + 1),
    };
    start.saturating_add(column).min(json.len())
}

/// The containers open at byte `offset` of `json`: every token starting before it counts.
fn frames_at(json: &[u8], offset: usize) -> Vec<Frame> {
    let mut frames: Vec<Frame> = Vec::new();
    let mut i = 0;
    while i < offset.min(json.len()) {
        match json[i] {
            b'{' => frames.push(Frame::Object {
                key: None,
                in_value: false,
            }),
            b'[' => frames.push(Frame::Array(0)),
            b'}' | b']' => {
                frames.pop();
            }
            b':' => {
                if let Some(Frame::Object { in_value, .. }) = frames.last_mut() {
                    *in_value = true;
                }
            }
            b',' => match frames.last_mut() {
                Some(Frame::Object { key, in_value }) => (*key, *in_value) = (None, false),
                Some(Frame::Array(n)) => *n += 1,
                None => {}
            },
            b'"' => {
                let end = string_end(json, i);
                if let Some(Frame::Object {
                    key,
                    in_value: false,
                }) = frames.last_mut()
                {
                    let raw = &json[i + 1..end.saturating_sub(1).max(i + 1)];
                    *key = Some(String::from_utf8_lossy(raw).into_owned());
                }
                i = end;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    frames
}

/// The offset just past the string that starts with the quote at `start` (or the end of
/// `json`, for a string cut off).
fn string_end(json: &[u8], start: usize) -> usize {
    let mut i = start + 1;
    while i < json.len() {
        match json[i] {
            b'\\' => i += 2,
            b'"' => return i + 1,
            _ => i += 1,
        }
    }
    json.len()
}

/// The JSON path of `frames`, as `meshes[0].primitives[1].indices`.
fn path(frames: &[Frame]) -> String {
    let mut at = String::new();
    for frame in frames {
        match frame {
            Frame::Object {
                key: Some(key),
                in_value: true,
            } => at = join(&at, key),
            Frame::Object { .. } => break,
            Frame::Array(n) => at.push_str(&format!("[{n}]")),
        }
    }
    at
}

/// `key` under `at`.
fn join(at: &str, key: &str) -> String {
    match at.is_empty() {
        true => key.to_owned(),
        false => format!("{at}.{key}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The error of reading `json` as a glTF document.
    fn error(json: &str) -> GltfError {
        let e = gltf::json::deserialize::from_slice::<gltf::json::Root>(json.as_bytes())
            .expect_err("an error");
        located(json.as_bytes(), &e)
    }

    #[test]
    fn data_errors_name_their_json_path_on_one_line_or_many() {
        let asset = r#""asset": {"version": "2.0"}"#;
        let missing =
            format!(r#"{{{asset}, "accessors": [{{"componentType": 5126, "count": 3}}]}}"#);
        let cases = [
            (missing.clone(), "accessors[0].type", "`type` is missing"),
            (
                missing.replace(", ", ",\n  "),
                "accessors[0].type",
                "`type` is missing",
            ),
            (
                format!(
                    r#"{{{asset}, "accessors": [{{"componentType": 5126, "count": 3, "type": "VEC3"}},
                        {{"componentType": 5126, "count": "3", "type": "VEC3"}}]}}"#
                ),
                "accessors[1].count",
                "invalid type",
            ),
            (
                format!(r#"{{{asset}, "scenes": [{{"nodes": [0, "one"]}}]}}"#),
                "scenes[0].nodes[1]",
                "invalid type",
            ),
            (r#"{"scenes": []}"#.into(), "asset", "`asset` is missing"),
            (
                format!(r#"{{{asset}, "meshes": [{{"primitives": [{{"mode": 4}}]}}]}}"#),
                "meshes[0].primitives[0].attributes",
                "`attributes` is missing",
            ),
            (
                format!(r#"{{{asset}, "nodes": [{{"name": "a \"quoted\" name", "matrix": 7}}]}}"#),
                "nodes[0].matrix",
                "invalid type",
            ),
            (
                format!(r#"{{{asset}, "nodes": [{{"mesh": [0]}}]}}"#),
                "nodes[0].mesh",
                "invalid type",
            ),
            (
                r#"{"asset": {"generator": "x"}}"#.into(),
                "asset.version",
                "is missing",
            ),
        ];
        for (json, at, message) in cases {
            let e = error(&json);
            assert_eq!(e.at, at, "{json}: {e}");
            assert!(e.message.contains(message), "{json}: {e}");
            assert!(!e.message.contains("line"), "{json}: {e}");
        }
    }

    #[test]
    fn syntax_errors_keep_their_line_and_column() {
        let e = error("{\"asset\": {\"version\": \"2.0\"},\n \"nodes\": [}");
        assert_eq!(e.at, "");
        assert!(e.message.contains("cannot be read"), "{e}");
        assert!(e.message.contains("line 2"), "{e}");
    }
}
