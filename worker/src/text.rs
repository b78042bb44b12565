//! Text from outside (an external strategy's stderr and stdout, a remote worker's error) made
//! safe to print on a terminal and to store: [`shown`].

/// The longest piece of outside text echoed in a message (bytes).
pub const MAX_ECHO_BYTES: usize = 300;

/// `s` with every control character written as an escape and cut to at most `max_bytes` bytes
/// (at a character boundary; "... (N more bytes)" says how much was left out). Escaped are the
/// C0 controls (NUL, BEL, ESC, ..., and `\n`, `\r`, `\t`, so that the text stays on one line),
/// DEL, the C1 controls, the line and paragraph separators and the bidirectional overrides and
/// isolates, which could move or recolour what a terminal shows; a backslash is kept as it is.
/// Escaping text already shown changes nothing.
pub fn shown(s: &str, max_bytes: usize) -> String {
    let mut out = String::with_capacity(s.len().min(max_bytes) + 16);
    let mut used = 0;
    for (i, c) in s.char_indices() {
        let piece = match c {
            '\n' => "\\n".to_string(),
            '\r' => "\\r".to_string(),
            '\t' => "\\t".to_string(),
            c if (c as u32) < 0x100 && c.is_control() => format!("\\x{:02x}", c as u32),
            c if unprintable(c).is_some() => format!("\\u{{{:04x}}}", c as u32),
            c => c.to_string(),
        };
        if used + piece.len() > max_bytes {
            out.push_str(&format!("... ({} more bytes)", s.len() - i));
            return out;
        }
        used += piece.len();
        out.push_str(&piece);
    }
    out
}

/// What kind of character `c` is when a terminal would not show it as itself: a control
/// character (C0, DEL, C1), a bidirectional control (an override, embedding, isolate or mark,
/// which reorders or hides what follows) or an invisible character (zero-width spaces and
/// joiners, the word joiner, invisible operators, the byte-order mark, the line and paragraph
/// separators); `None` for a printable character.
pub fn unprintable(c: char) -> Option<&'static str> {
    match c {
        c if c.is_control() => Some("a control character"),
        '\u{061c}'
        | '\u{200e}'
        | '\u{200f}'
        | '\u{202a}'..='\u{202e}'
        | '\u{2066}'..='\u{2069}' => Some("a bidirectional control character"),
        '\u{00ad}'
        | '\u{180e}'
        | '\u{200b}'..='\u{200d}'
        | '\u{2028}'
        | '\u{2029}'
        | '\u{2060}'..='\u{2064}'
        | '\u{206a}'..='\u{206f}'
        | '\u{feff}'
        | '\u{fff9}'..='\u{fffb}' => Some("an invisible character"),
        _ => None,
    }
}

/// The last `max_bytes` bytes (at most) of `s`, cut at a character boundary, after a line
/// saying how many bytes were left out before them, if any: the end of a program's stderr (a
/// traceback's last line says what went wrong).
pub fn tail(s: &str, max_bytes: usize) -> String {
    if s.len() <= max_bytes {
        return s.to_string();
    }
    let mut cut = s.len() - max_bytes;
    while !s.is_char_boundary(cut) {
        cut += 1;
    }
    format!(
        "[floorcast: the first {cut} bytes are left out]\n{}",
        &s[cut..]
    )
}

/// The most characters of outside text an error message quotes ([`excerpt`]).
pub const EXCERPT_CHARS: usize = 80;

/// Outside text (a value from a file, a name, a program's reply) as an error message quotes it:
/// escaped as [`shown`] escapes it, and at most [`EXCERPT_CHARS`] characters; a longer text is
/// cut with "..." and its length, so that what the message says after it is still read.
pub fn excerpt(s: &str) -> String {
    let mut chars = s.char_indices();
    match chars.nth(EXCERPT_CHARS) {
        None => shown(s, usize::MAX),
        Some((cut, _)) => format!(
            "{}... ({} characters in all)",
            shown(&s[..cut], usize::MAX),
            s.chars().count()
        ),
    }
}

/// A line of a library's message (a TOML parser's, which quotes the input's line and value)
/// kept to its first and last [`EXCERPT_CHARS`] characters when longer than three times that,
/// the cut saying the line's length: what the message says at its end (what was expected) stays.
pub fn shortened(line: &str) -> String {
    let n = line.chars().count();
    if n <= 3 * EXCERPT_CHARS {
        return line.to_string();
    }
    let head: String = line.chars().take(EXCERPT_CHARS).collect();
    let tail: String = line.chars().skip(n - EXCERPT_CHARS).collect();
    format!("{head} ... ({n} characters in all) ... {tail}")
}

#[cfg(test)]
mod tests {
    use super::{excerpt, shortened, shown, unprintable, EXCERPT_CHARS};

    #[test]
    fn long_lines_keep_their_ends() {
        assert_eq!(shortened("short line"), "short line");
        let line = format!("value \"{}\", expected a table", "x".repeat(100_000));
        let s = shortened(&line);
        assert!(s.len() < 300, "{s}");
        assert!(s.starts_with("value \"xxx"), "{s}");
        assert!(s.ends_with("\", expected a table"), "{s}");
        assert!(
            s.contains(&format!("({} characters in all)", line.len())),
            "{s}"
        );
    }

    #[test]
    fn excerpts_are_short_escaped_and_say_the_length() {
        assert_eq!(excerpt("short"), "short");
        assert_eq!(
            excerpt(&"x".repeat(EXCERPT_CHARS)),
            "x".repeat(EXCERPT_CHARS)
        );
        let long = "é".repeat(200_000);
        let e = excerpt(&long);
        assert_eq!(
            e,
            format!(
                "{}... (200000 characters in all)",
                "é".repeat(EXCERPT_CHARS)
            )
        );
        assert_eq!(excerpt("a\nb\u{200b}c"), "a\\nb\\u{200b}c");
        assert!(!excerpt(&"\x1b".repeat(500)).chars().any(char::is_control));
        assert!(excerpt(&"\x1b".repeat(500)).len() < 400);
    }

    /// The settings crate cuts a quoted name at its own copy of [`EXCERPT_CHARS`]: the same
    /// length as here.
    #[test]
    fn settings_quote_as_many_characters_as_excerpts() {
        let long = "k".repeat(EXCERPT_CHARS + 5);
        let e =
            crate::settings::settings_from_json_text(&format!("{{\"{long}\": 1}}")).unwrap_err();
        match e {
            crate::SettingsError::Unknown { field } => assert_eq!(field, excerpt(&long)),
            other => panic!("not an unknown setting: {other:?}"),
        }
    }

    #[test]
    fn invisible_and_bidi_characters_are_not_printable() {
        for c in [
            '\u{7}', '\n', '\u{9b}', '\u{202e}', '\u{2067}', '\u{200b}', '\u{200d}', '\u{2060}',
            '\u{feff}',
        ] {
            assert!(unprintable(c).is_some(), "{c:?}");
        }
        for c in ['a', 'é', ' ', '✓', '\u{301}', '漢'] {
            assert_eq!(unprintable(c), None, "{c:?}");
        }
        assert_eq!(shown("a\u{200b}b\u{feff}", 100), "a\\u{200b}b\\u{feff}");
    }

    #[test]
    fn control_characters_are_escaped() {
        let cases = [
            ("plain text", "plain text"),
            ("\x1b[31mred\x1b[0m", "\\x1b[31mred\\x1b[0m"),
            ("bell\x07 nul\0 del\x7f", "bell\\x07 nul\\x00 del\\x7f"),
            ("two\nlines\r\tx", "two\\nlines\\r\\tx"),
            ("c1 \u{9b}31m", "c1 \\x9b31m"),
            ("bidi \u{202e}abc\u{2066}", "bidi \\u{202e}abc\\u{2066}"),
            ("déjà vu ✓", "déjà vu ✓"),
            ("back\\slash", "back\\slash"),
        ];
        for (raw, want) in cases {
            assert_eq!(shown(raw, 1000), want, "{raw:?}");
            assert_eq!(shown(want, 1000), want, "twice: {raw:?}");
            assert!(!shown(raw, 1000).chars().any(char::is_control), "{raw:?}");
        }
    }

    #[test]
    fn long_text_is_cut_at_a_character() {
        let long = "é".repeat(100_000);
        let s = shown(&long, 300);
        assert!(s.len() < 340, "{}", s.len());
        assert!(s.starts_with(&"é".repeat(150)), "{s}");
        assert!(s.ends_with("... (199700 more bytes)"), "{s}");
        let esc = "\x1b".repeat(1000);
        let s = shown(&esc, 20);
        assert!(s.starts_with("\\x1b\\x1b\\x1b\\x1b\\x1b..."), "{s}");
        assert_eq!(shown("short", 5), "short");
    }
}
