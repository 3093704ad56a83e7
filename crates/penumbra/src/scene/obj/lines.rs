//! The line rules that OBJ and MTL files share, and the small word parsers both readers use.
//!
//! `#` starts a comment anywhere on a line; a line ending in `\` continues on the next one;
//! CRLF line endings, tabs and a UTF-8 byte-order mark are fine. (Bytes that are not UTF-8
//! are replaced before the text gets here, by the readers.)

use std::borrow::Cow;

/// Calls `f(line number, line)` for every logical line of `text`, comments removed and
/// `\`-continued lines joined (numbered by their first line).
pub(super) fn for_each_line(
    text: &str,
    f: impl FnMut(usize, &str) -> Result<(), String>,
) -> Result<(), String> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    for_each_line_from(text, 1, f)
}

/// [`for_each_line`] for a part of a file that starts with its line `first_line` (a byte-order
/// mark is kept: only the file's start may have one). The part must not begin inside a
/// `\`-continued line (see [`continues`]).
pub(super) fn for_each_line_from(
    text: &str,
    first_line: usize,
    mut f: impl FnMut(usize, &str) -> Result<(), String>,
) -> Result<(), String> {
    let mut pending = String::new();
    let mut pending_line = 0;
    // The physical lines as `text.split('\n')` gives them, each scanned once for its end and
    // its comment (a byte loop: much cheaper than two searches on lines this short).
    let bytes = text.as_bytes();
    let (mut start, mut n) = (0, first_line);
    while start <= bytes.len() {
        let (end, comment) = line_end(bytes, start);
        let line = text[start..comment.unwrap_or(end)].trim_end();
        let this = n;
        (start, n) = (end + 1, n + 1);
        let n = this;
        if let Some(head) = line.strip_suffix('\\') {
            if pending.is_empty() {
                pending_line = n;
            }
            pending.push_str(head);
            pending.push(' ');
            continue;
        }
        let (n, line) = if pending.is_empty() {
            (n, Cow::Borrowed(line))
        } else {
            pending.push_str(line);
            (pending_line, Cow::Owned(std::mem::take(&mut pending)))
        };
        f(n, &line)?;
    }
    if !pending.is_empty() {
        f(pending_line, &pending)?;
    }
    Ok(())
}

/// Where the physical line starting at `from` ends (its `\n`, or the end of `bytes`), and
/// where its comment starts, if it has one.
fn line_end(bytes: &[u8], from: usize) -> (usize, Option<usize>) {
    let stop = find(bytes, from, b'\n', b'#');
    if bytes.get(stop) == Some(&b'#') {
        (find(bytes, stop, b'\n', b'\n'), Some(stop))
    } else {
        (stop, None)
    }
}

/// The index of the first `a` or `b` in `bytes` from `from` on, or `bytes.len()`. Blocks of 16
/// bytes are tested without an early exit, which the compiler vectorizes.
pub(super) fn find(bytes: &[u8], from: usize, a: u8, b: u8) -> usize {
    let mut at = from;
    for block in bytes[from..].chunks_exact(16) {
        if block
            .iter()
            .fold(false, |hit, &c| hit | (c == a) | (c == b))
        {
            break;
        }
        at += 16;
    }
    bytes[at..]
        .iter()
        .position(|&c| c == a || c == b)
        .map_or(bytes.len(), |k| at + k)
}

/// The text of `bytes`, with every sequence that is not UTF-8 replaced by U+FFFD. Valid text
/// (nearly every file) is borrowed after one fast validation pass.
pub(super) fn decode(bytes: &[u8]) -> Cow<'_, str> {
    match std::str::from_utf8(bytes) {
        Ok(text) => Cow::Borrowed(text),
        Err(_) => String::from_utf8_lossy(bytes),
    }
}

/// A physical line (without its `\n`) with its comment and trailing whitespace removed.
fn content(raw: &str) -> &str {
    raw.find('#').map_or(raw, |k| &raw[..k]).trim_end()
}

/// True when the physical line `raw` (without its `\n`) continues on the next one.
pub(super) fn continues(raw: &str) -> bool {
    content(raw).ends_with('\\')
}

/// The first `N` numbers of `words`, at least `min` of them present; missing ones are 0.
/// Words after the first `N` are ignored (`v x y z w`, `v x y z r g b`).
pub(super) fn numbers<const N: usize>(
    words: &mut std::str::SplitAsciiWhitespace<'_>,
    min: usize,
) -> Option<[f32; N]> {
    let mut out = [0.0; N];
    let mut count = 0;
    for (slot, word) in out.iter_mut().zip(words) {
        *slot = word.parse().ok()?;
        count += 1;
    }
    (count >= min).then_some(out)
}

/// The text after `keyword` on `line`, trimmed (names may contain spaces).
///
/// `keyword` must be the line's first word as `split_ascii_whitespace` gives it: only ASCII
/// whitespace, which `trim_start` also removes, can precede it, so the slice is in bounds.
pub(super) fn rest_of_line<'a>(line: &'a str, keyword: &str) -> &'a str {
    line.trim_start()[keyword.len()..].trim()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The logical lines as the reader saw them when it split with `str::split('\n')` and
    /// `str::find('#')`: the byte scan must give the same lines and numbers.
    fn reference(text: &str, first_line: usize) -> Vec<(usize, String)> {
        let mut out = Vec::new();
        let (mut pending, mut pending_line) = (String::new(), 0);
        for (i, raw) in text.split('\n').enumerate() {
            let n = first_line + i;
            let line = raw.find('#').map_or(raw, |k| &raw[..k]).trim_end();
            if let Some(head) = line.strip_suffix('\\') {
                if pending.is_empty() {
                    pending_line = n;
                }
                pending.push_str(head);
                pending.push(' ');
                continue;
            }
            if pending.is_empty() {
                out.push((n, line.to_string()));
            } else {
                pending.push_str(line);
                out.push((pending_line, std::mem::take(&mut pending)));
            }
        }
        if !pending.is_empty() {
            out.push((pending_line, pending));
        }
        out
    }

    #[test]
    fn lines_and_numbers_match_splitting_by_str() {
        let texts = [
            "",
            "\n",
            "v 1 2 3",
            "v 1 2 3\n",
            "v 1 2 3\r\nv 4 5 6\r\n\r\n",
            "# only a comment\nv 1 2 3 # trailing\n#\n##\nf 1 2 3#x\n",
            "f 1 \\\n 2 \\\n 3\n\\\n",
            "f 1 2 \\ # a comment after the backslash\n3\n",
            "o Stätue ünïcode # kommentar ✓\n\tv\t1\t2\t3\t\n",
            "trailing backslash at the end \\",
        ];
        for text in texts {
            for first in [1, 40] {
                let mut got = Vec::new();
                for_each_line_from(text, first, |n, line| {
                    got.push((n, line.to_string()));
                    Ok(())
                })
                .unwrap();
                assert_eq!(got, reference(text, first), "{text:?}");
            }
        }
    }
}
