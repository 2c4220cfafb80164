//! [`Word`]: a short copy of something the user typed, kept in an error so that the message can
//! quote it (`'fly' is not a command`). Input lines are printable ASCII, at most 128 characters;
//! a quoted word keeps at most 24 of them.

/// A short copy of a word the user typed (longer words are cut and end in `...`).
pub type Word = heapless::String<24>;

/// Copies `text` into a [`Word`], cutting it with `...` if it does not fit.
pub fn word(text: &str) -> Word {
    let mut w = Word::new();
    if text.len() <= w.capacity() {
        // Fits: cannot fail.
        let _ = w.push_str(text);
    } else {
        let keep = w.capacity() - 3;
        // Input lines are ASCII, so byte slicing is on character boundaries; be safe anyway.
        let cut = (0..=keep)
            .rev()
            .find(|&i| text.is_char_boundary(i))
            .unwrap_or(0);
        let _ = w.push_str(&text[..cut]);
        let _ = w.push_str("...");
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_words_are_cut() {
        let w = word("abcdefghijklmnopqrstuvwxyz0123456789");
        assert_eq!(w.as_str(), "abcdefghijklmnopqrstu...");
        assert_eq!(word("short").as_str(), "short");
    }
}
