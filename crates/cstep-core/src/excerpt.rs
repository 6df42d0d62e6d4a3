//! Quoting what a user gave in an error without echoing all of it, so that a 60 000-character
//! name or a 15 MiB value still makes a one-line error. [`excerpt`] keeps the first
//! [`EXCERPT_CHARS`] characters and says how long the whole was.

use std::borrow::Cow;

/// The most characters of a value an error quotes.
pub const EXCERPT_CHARS: usize = 80;

/// `text` as an error quotes it: whole when it has at most [`EXCERPT_CHARS`] characters, else its
/// first [`EXCERPT_CHARS`] followed by `… (N characters)`; control characters (a line break in a
/// YAML block scalar) escaped as Rust escapes them (`\n`), so that the error stays one line.
pub fn excerpt(text: &str) -> Cow<'_, str> {
    let end = text.char_indices().nth(EXCERPT_CHARS).map(|(end, _)| end);
    let start = &text[..end.unwrap_or(text.len())];
    let shown: Cow<'_, str> = if start.contains(char::is_control) {
        start
            .chars()
            .map(|c| {
                if c.is_control() {
                    c.escape_default().to_string()
                } else {
                    c.to_string()
                }
            })
            .collect::<String>()
            .into()
    } else {
        start.into()
    };
    match end {
        None => shown,
        Some(_) => format!("{shown}… ({} characters)", text.chars().count()).into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_text_is_whole_and_long_text_its_start_and_length() {
        assert_eq!(excerpt("scan"), "scan");
        // Found by tests/yaml_fuzz.rs: a block scalar's line break made a two-line error.
        assert_eq!(excerpt("x y\nx\ty\n"), "x y\\nx\\ty\\n");
        let at_limit = "a".repeat(EXCERPT_CHARS);
        assert_eq!(excerpt(&at_limit), at_limit);
        let long = format!("/{}", "é".repeat(60_000));
        assert_eq!(
            excerpt(&long),
            format!("/{}… (60001 characters)", "é".repeat(EXCERPT_CHARS - 1))
        );
    }
}
