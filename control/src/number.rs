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
///
/// One pass over the bytes reads the sign and the mantissa's digits as a whole number (in
/// wrapping arithmetic: exact up to 9 digits) and how many follow the point; a short decimal
/// (at most 9 digits, a whole number of at most 2^24) is then converted at once
/// ([`short_decimal`]), anything else (an exponent, more digits) by core's parser: both give
/// the correctly rounded value, so which one does is a matter of speed only.
pub fn parse_f32(text: &str) -> Result<f32, NumberError> {
    let bytes = text.as_bytes();
    let (negative, unsigned) = match bytes {
        [b'-', rest @ ..] => (true, rest),
        [b'+', rest @ ..] => (false, rest),
        _ => (false, bytes),
    };
    let digit = |i: usize| {
        unsigned
            .get(i)
            .map(|b| b.wrapping_sub(b'0'))
            .filter(|&d| d < 10)
    };
    let mut whole: u32 = 0;
    let mut i = 0;
    while let Some(d) = digit(i) {
        whole = whole.wrapping_mul(10).wrapping_add(u32::from(d));
        i += 1;
    }
    let (mut after_point, point) = (0, unsigned.get(i) == Some(&b'.'));
    if point {
        i += 1;
        let from = i;
        while let Some(d) = digit(i) {
            whole = whole.wrapping_mul(10).wrapping_add(u32::from(d));
            i += 1;
        }
        after_point = i - from;
    }
    let digits = i - usize::from(point);
    let decimal = digits > 0 && (i == unsigned.len() || is_exponent(&unsigned[i..]));
    if !decimal {
        // (None of these words is a decimal: asked only of what is not one.)
        return Err(
            if ["nan", "inf", "infinity"]
                .iter()
                .any(|word| unsigned.eq_ignore_ascii_case(word.as_bytes()))
            {
                NumberError::NotFinite
            } else {
                NumberError::Syntax
            },
        );
    }
    if digits <= 9 && whole <= 1 << 24 && i == unsigned.len() {
        if let Some(value) = short_decimal(whole, after_point) {
            return Ok(if negative { -value } else { value });
        }
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

/// The value of an unsigned decimal of the grammar without an exponent whose digits make a
/// whole number `m` of at most 2^24 with `k` (at most 10) of them after the point (what people
/// type, e.g. `12.345`): `m / 10^k`, one `f32` division of two exact operands, which IEEE 754
/// rounds correctly, so it is exactly what core's parser gives (the "fast path" of W. D.
/// Clinger, "How to read floating point numbers accurately", 1990) at a fraction of its cost on
/// a chip without an FPU; no division at all without a fraction (`m / 1 = m`). `None` for more
/// than 10 digits after the point.
fn short_decimal(m: u32, k: usize) -> Option<f32> {
    let power = POWERS_OF_TEN.get(k)?;
    // Exact: at most 2^24 (on the chip the firmware's integer `__aeabi_ui2f`, ~32 cycles).
    let m = m as f32;
    Some(if k == 0 { m } else { m / power })
}

/// `("e" | "E") [sign] digits`, the whole of `bytes`.
fn is_exponent(bytes: &[u8]) -> bool {
    let rest = match bytes {
        [b'e' | b'E', b'+' | b'-', rest @ ..] | [b'e' | b'E', rest @ ..] => rest,
        _ => return false,
    };
    !rest.is_empty() && rest.iter().all(u8::is_ascii_digit)
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
        let mut next = crate::test_support::xorshift(0x2545_f491_u32);
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

    /// The documented result, from the grammar (checked here by a pattern of its own) and
    /// core's correctly rounded parser.
    fn documented(text: &str) -> Result<f32, NumberError> {
        let unsigned = text.strip_prefix(['+', '-']).unwrap_or(text);
        if ["nan", "inf", "infinity"]
            .iter()
            .any(|w| unsigned.eq_ignore_ascii_case(w))
        {
            return Err(NumberError::NotFinite);
        }
        let (mantissa, exponent) = match unsigned.find(['e', 'E']) {
            Some(at) => (&unsigned[..at], Some(&unsigned[at + 1..])),
            None => (unsigned, None),
        };
        let (int, frac) = mantissa.split_once('.').unwrap_or((mantissa, ""));
        let all_digits = |s: &str| s.bytes().all(|b| b.is_ascii_digit());
        let exponent_ok = exponent.is_none_or(|e| {
            let e = e.strip_prefix(['+', '-']).unwrap_or(e);
            !e.is_empty() && all_digits(e)
        });
        if int.len() + frac.len() == 0 || !all_digits(int) || !all_digits(frac) || !exponent_ok {
            return Err(NumberError::Syntax);
        }
        let v: f32 = text.parse().unwrap();
        if v.is_finite() {
            Ok(v)
        } else {
            Err(NumberError::TooLarge)
        }
    }

    #[test]
    fn random_texts_parse_as_documented() {
        // Short texts over the grammar's bytes and a few others: most are numbers, many not.
        let mut next = crate::test_support::xorshift(0x1234_5678_u32);
        let alphabet = b"0123456789012345678901234567890123456789..eE+-+-nafiINtyx ";
        for _ in 0..500_000 {
            let len = next() % 14;
            let text: std::string::String = (0..len)
                .map(|_| char::from(alphabet[(next() as usize) % alphabet.len()]))
                .collect();
            let (got, want) = (parse_f32(&text), documented(&text));
            assert_eq!(got.map(f32::to_bits), want.map(f32::to_bits), "{text:?}");
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
