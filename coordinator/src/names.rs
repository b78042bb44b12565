//! Names and labels of a grid (strategy labels, building names, the buildings that start poses
//! name): text that is shown in tables, charts and file names, and that identifies a
//! configuration. Each is kept as printable characters only, normalised (Unicode NFC, trimmed),
//! so that two names that look the same are the same name, and, when it becomes part of a file
//! name, without path separators or `..` and of a bounded length.

use floorcast_worker::text::{excerpt, unprintable};
use unicode_normalization::UnicodeNormalization;

/// The longest strategy label (characters): it heads a table column and a chart's legend.
pub const MAX_LABEL_CHARS: usize = 64;
/// The longest building name (characters): it becomes part of file names (charts).
pub const MAX_NAME_CHARS: usize = 100;

/// `text` as floorcast keeps it: in Unicode normalisation form C, without leading or trailing
/// white space. Refused when it holds a character a terminal does not show as itself (a control
/// character, a bidirectional control, an invisible character: [`unprintable`]) or is empty.
/// `what` says what was expected ("a short name such as \"nearest\"").
pub fn normalized(text: &str, what: &str) -> Result<String, String> {
    if let Some((i, c, kind)) = text
        .chars()
        .enumerate()
        .find_map(|(i, c)| unprintable(c).map(|k| (i, c, k)))
    {
        return Err(format!(
            "'{}' holds {kind} (U+{:04X}, character {} of {}); expected one line of printable characters",
            excerpt(text),
            c as u32,
            i + 1,
            text.chars().count()
        ));
    }
    let n: String = text.nfc().collect();
    let n = n.trim();
    if n.is_empty() {
        return Err(format!("is empty; expected {what}"));
    }
    Ok(n.to_string())
}

/// A strategy label ([`normalized`], at most [`MAX_LABEL_CHARS`] characters).
pub fn label(text: &str) -> Result<String, String> {
    let l = normalized(text, "a short name such as \"nearest\"")
        .map_err(|p| format!("the label {p}"))?;
    let n = l.chars().count();
    if n > MAX_LABEL_CHARS {
        return Err(format!(
            "the label '{}' is {n} characters long, more than {MAX_LABEL_CHARS}; give a short name",
            excerpt(&l)
        ));
    }
    Ok(l)
}

/// A building's name ([`normalized`]), which becomes part of file names (charts, outputs): no
/// path separator, no `..`, at most [`MAX_NAME_CHARS`] characters.
pub fn building_name(text: &str) -> Result<String, String> {
    let n = normalized(text, "a name such as \"school-a\"")?;
    file_name_part(&n)?;
    Ok(n)
}

/// Whether `name` may be part of a file name: no path separator (`/`, `\`), no `..`, at most
/// [`MAX_NAME_CHARS`] characters.
pub fn file_name_part(name: &str) -> Result<(), String> {
    let count = name.chars().count();
    if count > MAX_NAME_CHARS {
        return Err(format!(
            "'{}' is {count} characters long, more than {MAX_NAME_CHARS} (it becomes part of file names); give a shorter name",
            excerpt(name)
        ));
    }
    if name.contains(['/', '\\']) || name.contains("..") || name == "." {
        return Err(format!(
            "'{}' holds a path separator ('/' or '\\') or '..', and it becomes part of file names; use letters, digits, '-', '_' or single '.'",
            excerpt(name)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_normalised_and_trimmed() {
        assert_eq!(label(" near ").unwrap(), "near");
        // NFD "é" (e + combining acute) becomes NFC.
        assert_eq!(label("caf\u{65}\u{301}").unwrap(), "caf\u{e9}");
        assert_eq!(label("caf\u{e9}").unwrap(), "caf\u{e9}");
        assert_eq!(building_name("école ").unwrap(), "école");
    }

    #[test]
    fn unprintable_text_is_refused_naming_the_character() {
        for (text, needle) in [
            ("a\u{7}b", "U+0007"),
            ("a\nb", "U+000A"),
            ("near\u{200b}", "U+200B"),
            ("\u{202e}evil", "U+202E"),
            ("iso\u{2066}late", "U+2066"),
            ("\u{feff}bom", "U+FEFF"),
            ("zw\u{200d}j", "U+200D"),
            ("wj\u{2060}", "U+2060"),
        ] {
            let e = label(text).unwrap_err();
            assert!(e.contains(needle), "{text:?}: {e}");
            assert!(!e.chars().any(|c| unprintable(c).is_some()), "{e:?}");
            assert!(building_name(text).is_err(), "{text:?}");
        }
        assert!(label("   ").unwrap_err().contains("empty"));
    }

    #[test]
    fn file_name_parts_have_no_separator_no_dots_and_a_bound() {
        for bad in ["../x", "a/b", "a\\b", "..", ".", "x..y"] {
            assert!(building_name(bad).is_err(), "{bad}");
        }
        let long = "n".repeat(MAX_NAME_CHARS + 1);
        let e = building_name(&long).unwrap_err();
        assert!(e.contains("101 characters") && e.len() < 300, "{e}");
        assert!(building_name(&"n".repeat(MAX_NAME_CHARS)).is_ok());
        assert!(building_name("gen-school-500-4").is_ok());
        assert!(building_name("a.b").is_ok());
        let e = label(&"l".repeat(65)).unwrap_err();
        assert!(e.contains("65 characters"), "{e}");
    }
}
