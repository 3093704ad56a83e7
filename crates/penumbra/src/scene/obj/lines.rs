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
    for (i, raw) in text.split('\n').enumerate() {
        let n = first_line + i;
        let line = content(raw);
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
