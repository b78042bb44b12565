//! Mutations of valid files for the fuzz tests of every reader (this crate's, the grid's, the
//! settings'): one implementation, each caller giving the tokens that matter to its format.
//! Compiled for this crate's tests and, with the `test-support` feature, for other crates' tests.

/// `text` changed by `edits` (position, operation, byte), in order: replace a byte, insert one,
/// delete one, insert one of `tokens` (chosen by the byte; nothing when `tokens` is empty), or
/// insert two more copies of the stretch of up to 16 bytes that starts there. Positions wrap
/// around the text's length.
pub fn mutate(text: &str, edits: &[(usize, u8, u8)], tokens: &[&[u8]]) -> String {
    let mut b = text.as_bytes().to_vec();
    for &(pos, op, byte) in edits {
        let i = pos % (b.len() + 1);
        match op % 5 {
            0 if i < b.len() => b[i] = byte,
            1 => b.insert(i, byte),
            2 if i < b.len() => {
                b.remove(i);
            }
            3 => {
                if let Some(t) = tokens.get(byte as usize % tokens.len().max(1)) {
                    b.splice(i..i, t.iter().copied());
                }
            }
            _ => {
                let end = (i + 1 + byte as usize % 16).min(b.len());
                let piece: Vec<u8> = b[i.min(end)..end].to_vec();
                b.splice(i..i, piece.iter().copied().chain(piece.iter().copied()));
            }
        }
    }
    String::from_utf8_lossy(&b).into_owned()
}

#[cfg(test)]
mod tests {
    use super::mutate;

    /// Edits, and what they make of "abc".
    type Case = (&'static [(usize, u8, u8)], &'static str);

    #[test]
    fn each_operation_does_what_it_says() {
        let cases: &[Case] = &[
            (&[], "abc"),
            (&[(1, 0, b'x')], "axc"),
            (&[(3, 0, b'x')], "abc"),
            (&[(1, 1, b'x')], "axbc"),
            (&[(1, 2, 0)], "ac"),
            (&[(0, 3, 1)], "[abc"),
            (&[(0, 3, 0)], "nanabc"),
            (&[(0, 4, 1)], "abababc"),
            (&[(7, 1, b'x')], "abcx"),
            (&[(1, 2, 0), (1, 2, 0)], "a"),
        ];
        for (edits, want) in cases {
            assert_eq!(mutate("abc", edits, &[b"nan", b"["]), *want, "{edits:?}");
        }
        assert_eq!(mutate("abc", &[(0, 3, 5)], &[]), "abc");
        assert_eq!(mutate("", &[(5, 2, 0), (5, 0, 1)], &[]), "");
    }
}
