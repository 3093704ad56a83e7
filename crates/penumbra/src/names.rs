//! Names from files made safe where they go: inside file names and inside messages.
//!
//! A camera's or a view's name put into an output pattern such as `out/{camera}.png` must stay
//! one file name in the pattern's folder, whatever the scene or the jobs file calls it: one rule
//! ([`file_name_part`]) for the command line's `{camera}` and for Python's batches (`{name}`),
//! so that a name gives the same file everywhere. A name or string quoted in a message is
//! escaped ([`escape_controls`]) so that the message stays one line.
//!
//! ```
//! use penumbra::{escape_controls, file_name_part};
//!
//! assert_eq!(file_name_part("front"), "front");
//! assert_eq!(file_name_part("side/left"), "side_left");
//! assert_eq!(file_name_part(".."), "_.");
//! assert_eq!(escape_controls("a\nb"), "a\\nb");
//! ```

/// `text` with every control character (newline, ESC, BEL, ...) written as a Rust escape
/// such as `\n` or `\u{1b}`: names and strings from a file reach messages this way, so one
/// message stays one line and cannot drive the terminal that shows it.
pub fn escape_controls(text: &str) -> String {
    if !text.chars().any(char::is_control) {
        return text.to_owned();
    }
    text.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// `name` as a part of one file name: every path separator (`/`, `\`), drive colon (`:`) and
/// control character (NUL, newline, escape, ...) becomes `_`, and so does a leading `.` or `-`
/// (so no name is `.`, `..` or a hidden file, nor reads as an option to other tools); an
/// empty name is `_`. Other names, Unicode included, are kept as they are.
pub fn file_name_part(name: &str) -> String {
    if name.is_empty() {
        return "_".to_owned();
    }
    name.chars()
        .enumerate()
        .map(|(i, c)| {
            let path_syntax = matches!(c, '/' | '\\' | ':') || c.is_control();
            let leading = i == 0 && matches!(c, '.' | '-');
            if path_syntax || leading {
                '_'
            } else {
                c
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::file_name_part;

    #[test]
    fn names_stay_one_file_name() {
        let cases = [
            ("front", "front"),
            ("side/left", "side_left"),
            ("..", "_."),
            (".", "_"),
            ("../../etc/passwd", "_._.._etc_passwd"),
            ("a\\b", "a_b"),
            ("C:", "C_"),
            ("nul\0byte", "nul_byte"),
            ("line\nbreak\u{1b}[31m", "line_break_[31m"),
            ("-rf", "_rf"),
            (".hidden", "_hidden"),
            ("", "_"),
            ("a.b-c d", "a.b-c d"),
            ("café", "café"),
        ];
        for (name, want) in cases {
            let got = file_name_part(name);
            assert_eq!(got, want, "{name:?}");
            assert!(
                !got.is_empty() && got != "." && got != ".." && !got.contains(['/', '\\', '\0']),
                "{name:?} -> {got:?}"
            );
        }
    }
}
