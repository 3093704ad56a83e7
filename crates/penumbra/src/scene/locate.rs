//! Finds where a key path sits in a scene file's text, so that errors found after parsing
//! (an unknown material name, a value out of range) still point at a line and column.

use toml::de::{DeTable, DeValue};

use super::error::{KeyPath, Segment};
use super::SceneFormat;

/// Byte offset of the value (or, for a table key, of the key) that `path` names: the deepest
/// part of the path that exists, or the start of the file when none does.
pub(crate) fn locate(text: &str, format: SceneFormat, path: &KeyPath) -> Option<usize> {
    match format {
        SceneFormat::Toml => locate_toml(text, path),
        SceneFormat::Json => locate_json(text, path),
    }
}

fn locate_toml(text: &str, path: &KeyPath) -> Option<usize> {
    let root = DeTable::parse(text).ok()?;
    let mut offset = Some(0);
    let mut table: Option<&DeTable> = Some(root.get_ref());
    let mut value: Option<&DeValue> = None;
    for seg in &path.0 {
        match seg {
            Segment::Key(k) => {
                let t = table.take().or_else(|| value.and_then(DeValue::as_table))?;
                let Some((key, v)) = t.iter().find(|(key, _)| key.get_ref().as_ref() == k) else {
                    return offset;
                };
                offset = Some(key.span().start);
                value = Some(v.get_ref());
            }
            Segment::Index(i) => {
                let Some(v) = value.and_then(DeValue::as_array).and_then(|a| a.get(*i)) else {
                    return offset;
                };
                offset = Some(v.span().start);
                value = Some(v.get_ref());
            }
        }
    }
    offset
}

/// The key path of the TOML key at byte `offset`, from the text alone, for errors the parser
/// finds before any table exists (a duplicate key, nesting too deep): the table that the
/// nearest header above opens (`[[objects]]` counted into `objects[i]`), then the dotted key of
/// the nearest `key = ` line at or above `offset`. On a header line, the header's own path.
pub(crate) fn toml_path_at(text: &str, offset: usize) -> KeyPath {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let line_end = text[offset..].find('\n').map_or(text.len(), |i| offset + i);
    let mut table = KeyPath(Vec::new());
    let mut arrays: Vec<(String, usize)> = Vec::new();
    let mut key_line: Option<&str> = None;
    for line in text[..line_end].split('\n') {
        match toml_header(line) {
            Some((name, is_array)) => {
                let keys = split_dotted(name);
                let mut path = KeyPath(keys.iter().map(|k| Segment::Key(k.clone())).collect());
                if is_array {
                    let joined = keys.join(".");
                    let count = match arrays.iter_mut().find(|(n, _)| *n == joined) {
                        Some((_, c)) => {
                            *c += 1;
                            *c
                        }
                        None => {
                            arrays.push((joined, 0));
                            0
                        }
                    };
                    path = path.index(count);
                }
                table = path;
                key_line = None;
            }
            None => {
                if let Some((key, _)) = line.split_once('=') {
                    // A key, not a string or row inside a multi-line array.
                    let quotes = key.matches(['"', '\'']).count();
                    let is_key = !key.trim().is_empty() && !key.contains(['[', '{', ',']);
                    if is_key && quotes % 2 == 0 {
                        key_line = Some(key);
                    }
                }
            }
        }
    }
    match key_line {
        Some(key) => split_dotted(key).iter().fold(table, |path, k| path.key(k)),
        None => table,
    }
}

/// The byte offset of the TOML line whose header or key is dotted deepest (the first such), for
/// a nesting-depth error that the deserializer reports without a place.
pub(crate) fn deepest_toml_line(text: &str) -> Option<usize> {
    let mut best: Option<(usize, usize)> = None;
    let mut start = 0;
    for line in text.split('\n') {
        let name = toml_header(line).map(|(name, _)| name).or_else(|| {
            let (key, _) = line.split_once('=')?;
            (!key.contains(['[', '{', ',', '"', '\''])).then_some(key)
        });
        let depth = name.map_or(0, |n| split_dotted(n).len());
        if depth > best.map_or(0, |(d, _)| d) {
            best = Some((depth, start));
        }
        start += line.len() + 1;
    }
    best.map(|(_, offset)| offset)
}

/// The name in a `[name]` or `[[name]]` header line, and whether it is an array of tables.
fn toml_header(line: &str) -> Option<(&str, bool)> {
    let t = line.trim();
    let t = t.find('#').map_or(t, |i| t[..i].trim_end());
    let (inner, is_array) = if let Some(rest) = t.strip_prefix("[[") {
        (rest.strip_suffix("]]")?, true)
    } else {
        (t.strip_prefix('[')?.strip_suffix(']')?, false)
    };
    // A key, not the row of a multi-line array (`[0, 1],`, `[1]`).
    let key_like = |c: char| c.is_alphanumeric() || "_-. \"'".contains(c);
    (!inner.trim().is_empty()
        && inner.chars().all(key_like)
        && inner.chars().any(|c| c.is_alphabetic()))
    .then_some((inner, is_array))
}

/// The parts of a dotted key, unquoted: `a."b.c" . d` → a, b.c, d.
fn split_dotted(key: &str) -> Vec<String> {
    let mut parts = Vec::new();
    let mut current = String::new();
    let mut quote: Option<char> = None;
    for c in key.trim().chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), c) => current.push(c),
            (None, '"' | '\'') => quote = Some(c),
            (None, '.') => parts.push(std::mem::take(&mut current).trim().to_owned()),
            (None, c) => current.push(c),
        }
    }
    parts.push(current.trim().to_owned());
    parts
}

/// A scanner over JSON text that serde_json has already accepted, so it only needs to step
/// over values, never to report syntax errors.
struct Json<'a> {
    b: &'a [u8],
    i: usize,
}

impl Json<'_> {
    fn ws(&mut self) {
        while self.i < self.b.len() && self.b[self.i].is_ascii_whitespace() {
            self.i += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.ws();
        self.b.get(self.i).copied()
    }

    /// Steps over a string starting at `self.i` (at its quote); returns its raw contents.
    fn string(&mut self) -> &[u8] {
        let start = self.i + 1;
        self.i += 1;
        while self.i < self.b.len() && self.b[self.i] != b'"' {
            if self.b[self.i] == b'\\' {
                self.i += 1;
            }
            self.i += 1;
        }
        let s = &self.b[start..self.i.min(self.b.len())];
        self.i += 1;
        s
    }

    fn skip_value(&mut self) {
        let mut depth = 0usize;
        loop {
            match self.peek() {
                None => return,
                Some(b'"') => {
                    self.string();
                }
                Some(b'{' | b'[') => {
                    depth += 1;
                    self.i += 1;
                }
                Some(b'}' | b']') => {
                    depth = depth.saturating_sub(1);
                    self.i += 1;
                }
                Some(b',' | b':') if depth > 0 => self.i += 1,
                Some(_) => {
                    while self.i < self.b.len() && !b",]}: \t\r\n".contains(&self.b[self.i]) {
                        self.i += 1;
                    }
                }
            }
            if depth == 0 {
                return;
            }
        }
    }
}

fn locate_json(text: &str, path: &KeyPath) -> Option<usize> {
    let mut p = Json {
        b: text.as_bytes(),
        i: 0,
    };
    p.ws();
    let mut offset = Some(p.i);
    for seg in &path.0 {
        match seg {
            Segment::Key(k) => {
                if p.peek()? != b'{' {
                    return offset;
                }
                p.i += 1;
                loop {
                    match p.peek()? {
                        b'}' => return offset,
                        b',' => p.i += 1,
                        b'"' => {
                            let start = p.i;
                            let raw = p.string();
                            let key: String =
                                serde_json::from_slice(&[b"\"".as_slice(), raw, b"\""].concat())
                                    .unwrap_or_default();
                            p.peek();
                            p.i += 1; // ':'
                            if key == *k {
                                offset = Some(start);
                                break;
                            }
                            p.skip_value();
                        }
                        _ => return offset,
                    }
                }
            }
            Segment::Index(n) => {
                if p.peek()? != b'[' {
                    return offset;
                }
                p.i += 1;
                for _ in 0..*n {
                    p.skip_value();
                    if p.peek()? != b',' {
                        return offset;
                    }
                    p.i += 1;
                }
                if p.peek()? == b']' {
                    return offset;
                }
                offset = Some(p.i);
            }
        }
    }
    offset
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::error::line_col;

    fn at(text: &str, format: SceneFormat, path: KeyPath) -> (usize, usize) {
        line_col(text, locate(text, format, &path).unwrap())
    }

    #[test]
    fn finds_keys_in_toml_tables_and_arrays_of_tables() {
        let text = "[film]\nwidth = 1\n\n[[objects]]\ntype = \"cube\"\n\n[[objects]]\ntype = \"quad\"\n  material = \"x\"\n";
        let objects = KeyPath::root("objects");
        assert_eq!(
            at(text, SceneFormat::Toml, KeyPath::root("film").key("width")),
            (2, 1)
        );
        assert_eq!(
            at(text, SceneFormat::Toml, objects.index(1).key("material")),
            (9, 3)
        );
        // A missing key points at the deepest part that exists.
        let (line, _) = at(text, SceneFormat::Toml, objects.index(1).key("nothing"));
        assert!(line >= 7, "line {line}");
    }

    #[test]
    fn names_the_toml_key_at_an_offset() {
        let text = "[film]\nwidth = 1\n\n[[objects]]\ntype = \"cube\"\n\n[[objects]]\ntype = \"quad\"\nu = [\n  [1],\n  [0, 0, 1]\n]\n  a.\"b.c\" = 2\n[materials.red]\n";
        let path_at = |needle: &str| toml_path_at(text, text.find(needle).unwrap()).to_string();
        assert_eq!(path_at("width"), "film.width");
        assert_eq!(path_at("quad"), "objects[1].type");
        assert_eq!(path_at("[0, 0, 1]"), "objects[1].u");
        assert_eq!(path_at("[1]"), "objects[1].u");
        assert_eq!(path_at("a."), "objects[1].a.b.c");
        assert_eq!(path_at("red]"), "materials.red");
    }

    #[test]
    fn finds_keys_in_json() {
        let text = "{\n  \"film\": {\"width\": 1},\n  \"objects\": [\n    {\"type\": \"cube\", \"size\": [1, {\"a\": \"]\"}]},\n    {\"type\": \"quad\",\n     \"material\": \"x\"}\n  ]\n}\n";
        let objects = KeyPath::root("objects");
        assert_eq!(
            at(text, SceneFormat::Json, KeyPath::root("film").key("width")),
            (2, 12)
        );
        assert_eq!(
            at(text, SceneFormat::Json, objects.index(1).key("material")),
            (6, 6)
        );
        assert_eq!(at(text, SceneFormat::Json, objects.index(1)), (5, 5));
    }
}
