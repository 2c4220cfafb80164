//! Strict number parsing for what users type.
//!
//! Accepted decimals: an optional sign, digits with an optional fraction (`12`, `-0.5`, `.5`,
//! `5.`), and an optional exponent (`1e3`, `2.5E-2`). Everything else is refused, including
//! the forms `core::str::parse::<f32>` would accept or that look like numbers in other
//! languages: `nan`, `inf`, `infinity`, `0x10`, `1_000`, `+-1`, `1e`, empty text. A decimal
//! that is syntactically fine but does not fit an `f32` (`1e39`) is its own error, so every
//! successful result is finite.
//!
//! Whole numbers (`frame_hz`, `baud`) use [`parse_u32`]: digits only, no sign, no fraction.

/// Why a word is not a usable number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NumberError {
    /// Not a decimal number at all (`abc`, `0x10`, `1.2.3`, empty).
    Syntax,
    /// One of the words for a non-finite value (`nan`, `inf`, `infinity`, signed or not).
    NotFinite,
    /// A decimal whose magnitude does not fit an `f32` (about 3.4e38) or a `u32`.
    TooLarge,
    /// A decimal with a fraction or exponent where a whole number is needed.
    NotWhole,
}

/// Parses a strict decimal (see the module docs). The text must already be trimmed.
pub fn parse_f32(text: &str) -> Result<f32, NumberError> {
    let unsigned = text
        .strip_prefix('-')
        .or_else(|| text.strip_prefix('+'))
        .unwrap_or(text);
    if !is_decimal(unsigned.as_bytes()) {
        // (None of these words is a decimal: asked only of what is not one.)
        return Err(
            if ["nan", "inf", "infinity"]
                .iter()
                .any(|word| unsigned.eq_ignore_ascii_case(word))
            {
                NumberError::NotFinite
            } else {
                NumberError::Syntax
            },
        );
    }
    if let Some(value) = short_decimal(unsigned.as_bytes()) {
        return Ok(if text.starts_with('-') { -value } else { value });
    }
    // The grammar above is a subset of what core's correctly rounded parser accepts.
    let value: f32 = text.parse().map_err(|_| NumberError::Syntax)?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(NumberError::TooLarge)
    }
}

/// Parses a whole number: ASCII digits only (a fraction or exponent is [`NumberError::NotWhole`]).
pub fn parse_u32(text: &str) -> Result<u32, NumberError> {
    let bytes = text.as_bytes();
    if bytes.is_empty() || !bytes.iter().all(u8::is_ascii_digit) {
        // Distinguish "50.5" (a number, but not whole) from "abc".
        return match parse_f32(text) {
            Ok(_) => Err(NumberError::NotWhole),
            Err(e) => Err(e),
        };
    }
    let mut value: u32 = 0;
    for &b in bytes {
        value = value
            .checked_mul(10)
            .and_then(|v| v.checked_add(u32::from(b - b'0')))
            .ok_or(NumberError::TooLarge)?;
    }
    Ok(value)
}

/// `10^k` for `k` in `0..=10`, each exact in an `f32` (`10^k = 2^k 5^k`, `5^10 < 2^24`).
const POWERS_OF_TEN: [f32; 11] = [1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10];

/// The value of an unsigned decimal of the grammar ([`is_decimal`]) without an exponent whose
/// digits make a whole number `m` of at most 2^24 with at most 10 of them after the point (what
/// people type, e.g. `12.345`): `m / 10^k`, one `f32` division of two exact operands, which
/// IEEE 754 rounds correctly, so it is exactly what core's parser gives (the "fast path" of
/// W. D. Clinger, "How to read floating point numbers accurately", 1990) at a fraction of its
/// cost on a chip without an FPU. `None` for any other decimal.
fn short_decimal(bytes: &[u8]) -> Option<f32> {
    let mut whole: u32 = 0;
    let mut after_point = false;
    let mut fraction_digits = 0;
    for &b in bytes {
        match b {
            b'0'..=b'9' => {
                // At most 2^24 before, so no overflow.
                whole = whole * 10 + u32::from(b - b'0');
                if whole > 1 << 24 {
                    return None;
                }
                fraction_digits += usize::from(after_point);
            }
            b'.' => after_point = true,
            _ => return None, // an exponent
        }
    }
    let power = POWERS_OF_TEN.get(fraction_digits)?;
    // (`whole` is exact in an f32.)
    Some(whole as f32 / power)
}

/// `digits [ "." digits ] [ exponent ]` or `"." digits [ exponent ]`, at least one mantissa
/// digit, exponent `("e" | "E") [sign] digits`.
fn is_decimal(bytes: &[u8]) -> bool {
    let digits = |s: &[u8]| s.iter().take_while(|b| b.is_ascii_digit()).count();
    let int_len = digits(bytes);
    let mut i = int_len;
    let mut frac_len = 0;
    if bytes.get(i) == Some(&b'.') {
        i += 1;
        frac_len = digits(&bytes[i..]);
        i += frac_len;
    }
    if int_len + frac_len == 0 {
        return false;
    }
    if matches!(bytes.get(i), Some(b'e' | b'E')) {
        i += 1;
        if matches!(bytes.get(i), Some(b'+' | b'-')) {
            i += 1;
        }
        let exp_len = digits(&bytes[i..]);
        if exp_len == 0 {
            return false;
        }
        i += exp_len;
    }
    i == bytes.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepts_plain_decimals() {
        assert_eq!(parse_f32("12"), Ok(12.0));
        assert_eq!(parse_f32("-0.5"), Ok(-0.5));
        assert_eq!(parse_f32("+3.25"), Ok(3.25));
        assert_eq!(parse_f32(".5"), Ok(0.5));
        assert_eq!(parse_f32("5."), Ok(5.0));
        assert_eq!(parse_f32("1e3"), Ok(1000.0));
        assert_eq!(parse_f32("2.5E-2"), Ok(0.025));
        assert_eq!(parse_f32("-0"), Ok(0.0));
        assert_eq!(parse_f32("007"), Ok(7.0));
    }

    #[test]
    fn tiny_values_round_to_zero() {
        assert_eq!(parse_f32("1e-60"), Ok(0.0));
    }

    #[test]
    fn non_finite_words_are_their_own_error() {
        for word in [
            "nan", "NaN", "-nan", "inf", "+inf", "-INF", "infinity", "Infinity",
        ] {
            assert_eq!(parse_f32(word), Err(NumberError::NotFinite), "{word}");
        }
    }

    #[test]
    fn overflow_is_its_own_error() {
        for word in [
            "1e39",
            "-1e39",
            "350000000000000000000000000000000000000",
            "1e99999",
        ] {
            assert_eq!(parse_f32(word), Err(NumberError::TooLarge), "{word}");
        }
        // The largest f32 itself is fine.
        assert_eq!(parse_f32("3.4028234e38"), Ok(f32::MAX));
    }

    #[test]
    fn everything_else_is_a_syntax_error() {
        for word in [
            "", "-", "+", ".", "abc", "0x10", "1_000", "1.2.3", "+-1", "--1", "1e", "1e+", "e5",
            "1,5", " 1", "1 ", "1.5x", "infx", "nana", "١",
        ] {
            assert_eq!(parse_f32(word), Err(NumberError::Syntax), "{word:?}");
        }
    }

    #[test]
    fn whole_numbers() {
        assert_eq!(parse_u32("115200"), Ok(115_200));
        assert_eq!(parse_u32("0"), Ok(0));
        assert_eq!(parse_u32("4294967295"), Ok(u32::MAX));
        assert_eq!(parse_u32("4294967296"), Err(NumberError::TooLarge));
        assert_eq!(parse_u32("50.5"), Err(NumberError::NotWhole));
        assert_eq!(parse_u32("5e1"), Err(NumberError::NotWhole));
        assert_eq!(parse_u32("-5"), Err(NumberError::NotWhole));
        assert_eq!(parse_u32("x"), Err(NumberError::Syntax));
        assert_eq!(parse_u32("nan"), Err(NumberError::NotFinite));
        assert_eq!(parse_u32(""), Err(NumberError::Syntax));
    }

    #[test]
    fn short_decimals_are_what_the_correctly_rounded_parser_gives() {
        // The fast path against core's parser, bit for bit: random digits up to 2^24 and
        // past it, 0 to 12 of them after the point, signs, leading and trailing zeros.
        let mut seed = 0x2545_f491_u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        };
        for _ in 0..300_000 {
            let digits = (next() % (1 << 25)).to_string();
            let zeros = "0".repeat((next() % 3) as usize);
            let digits = format!("{zeros}{digits}{zeros}");
            let point = (next() as usize) % (digits.len() + 1);
            let sign = ["", "-", "+"][(next() % 3) as usize];
            let text = format!("{sign}{}.{}", &digits[..point], &digits[point..]);
            let text = text.trim_end_matches('.').to_string();
            let expected: f32 = text.parse().unwrap();
            assert_eq!(
                parse_f32(&text).map(f32::to_bits),
                Ok(expected.to_bits()),
                "{text}"
            );
        }
        // The edges of the fast path, each side.
        for text in [
            "16777216",
            "16777217",
            "1677721.6",
            "0.1234567891",
            "0.12345678912",
            "1.0000000000",
            "1.00000000000",
            "-0.0",
            ".5",
            "5.",
        ] {
            let expected: f32 = text.parse().unwrap();
            assert_eq!(
                parse_f32(text).map(f32::to_bits),
                Ok(expected.to_bits()),
                "{text}"
            );
        }
    }

    proptest::proptest! {
        #[test]
        fn never_panics_and_results_are_finite(s in "\\PC{0,40}") {
            if let Ok(v) = parse_f32(&s) {
                proptest::prop_assert!(v.is_finite());
            }
        }

        #[test]
        fn formatted_floats_parse_back(v in -1.0e30f32..1.0e30) {
            let text = format!("{v}");
            proptest::prop_assert_eq!(parse_f32(&text), Ok(v));
            let text = format!("{v:e}");
            proptest::prop_assert_eq!(parse_f32(&text), Ok(v));
        }
    }
}
