//! Names from files made safe where they go: inside file names and inside messages; and the
//! error for a name outside a closed set (a sampler, an image format).
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

/// A name that is none of a closed set's, such as `"sobol"` for a sampler: the error of the
/// `FromStr` of [`Sampler`](crate::Sampler), [`OutputFormat`](crate::OutputFormat),
/// [`Shading`](crate::Shading) and [`LightModel`](crate::LightModel). The message lists the
/// names there are.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown {what} {name:?} (use {})", quoted_list(known))]
pub struct UnknownName {
    /// What the name was meant to name ("sampler", "image format", ...).
    pub what: &'static str,
    /// The name given.
    pub name: String,
    /// The names there are, in their usual order.
    pub known: Vec<&'static str>,
}

/// The member of `all` that `name_of` calls `name`, else an [`UnknownName`] of `what`.
pub(crate) fn parse_name<T: Copy>(
    what: &'static str,
    name: &str,
    all: &[T],
    name_of: impl Fn(T) -> &'static str,
) -> Result<T, UnknownName> {
    all.iter()
        .copied()
        .find(|&t| name_of(t) == name)
        .ok_or_else(|| UnknownName {
            what,
            name: name.to_owned(),
            known: all.iter().map(|&t| name_of(t)).collect(),
        })
}

/// `"a", "b" or "c"`.
fn quoted_list(names: &[&str]) -> String {
    let quoted: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
    match quoted.split_last() {
        None => String::new(),
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unknown_name_lists_the_known_ones() {
        let e = UnknownName {
            what: "sampler",
            name: "so\"bol".into(),
            known: vec!["center", "grid", "rgss"],
        };
        assert_eq!(
            e.to_string(),
            r#"unknown sampler "so\"bol" (use "center", "grid" or "rgss")"#
        );
        assert_eq!(quoted_list(&["png"]), "\"png\"");
    }

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
