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
            '\u{2028}' | '\u{2029}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}' => {
                format!("\\u{{{:04x}}}", c as u32)
            }
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

#[cfg(test)]
mod tests {
    use super::shown;

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
