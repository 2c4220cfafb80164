//! Compile-time `f64` maths for the look-up tables of the fixed-point routines: each table is
//! a `const` computed when the crate is built (Rust evaluates floating-point arithmetic in
//! `const` contexts with IEEE-754 semantics, the same on every machine), so no table is typed
//! in by hand and each one is checked against `libm` by the tests.
//!
//! The series below are accurate to a few units in the last place of an `f64` (about 1e-16)
//! over the ranges their callers use, far below the 2^-33 to which the tables are rounded.

/// `sin x` for `|x| <= pi/2`, by its Taylor series `x - x^3/3! + x^5/5! - ...` up to `x^41`
/// (the next term is below 1e-40 there).
pub(crate) const fn sin(x: f64) -> f64 {
    let x2 = x * x;
    let (mut term, mut sum) = (x, x);
    let mut n = 1;
    while n < 41 {
        term = -term * x2 / ((n + 1) * (n + 2)) as f64;
        sum += term;
        n += 2;
    }
    sum
}

/// `sqrt x` for `x > 0` by Newton's iteration `r <- (r + x / r) / 2` from `r = max(x, 1)`
/// (which is above the root, so the iteration decreases monotonically to it), until it stops
/// decreasing.
pub(crate) const fn sqrt(x: f64) -> f64 {
    let mut r = if x > 1.0 { x } else { 1.0 };
    loop {
        let next = 0.5 * (r + x / r);
        if next >= r {
            return r;
        }
        r = next;
    }
}

/// `atan t` for `0 <= t <= 1`: the argument is halved three times with
/// `atan t = 2 atan(t / (1 + sqrt(1 + t^2)))` (to at most `tan(pi/32)`, about 0.1), then the
/// Taylor series `t - t^3/3 + t^5/5 - ...` to `t^61`.
pub(crate) const fn atan(t: f64) -> f64 {
    let mut t = t;
    let mut halvings = 0;
    while halvings < 3 {
        t /= 1.0 + sqrt(1.0 + t * t);
        halvings += 1;
    }
    let t2 = t * t;
    let (mut power, mut sum) = (t, t);
    let mut n = 3;
    while n <= 61 {
        power = -power * t2;
        sum += power / n as f64;
        n += 2;
    }
    sum * 8.0
}

/// `x` rounded to the nearest integer (halves away from zero).
pub(crate) const fn round(x: f64) -> i64 {
    if x >= 0.0 {
        (x + 0.5) as i64
    } else {
        -((-x + 0.5) as i64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compile_time_series_match_libm() {
        for i in 0..=1000 {
            let t = f64::from(i) / 1000.0;
            let x = t * core::f64::consts::FRAC_PI_2;
            assert!((sin(x) - libm::sin(x)).abs() < 4e-16, "sin {x}");
            assert!((atan(t) - libm::atan(t)).abs() < 4e-16, "atan {t}");
            let y = 0.25 + 4.0 * t;
            assert!(
                (sqrt(y) - libm::sqrt(y)).abs() <= 2.0 * f64::EPSILON * y,
                "sqrt {y}"
            );
        }
        assert_eq!(round(2.5), 3);
        assert_eq!(round(-2.5), -3);
        assert_eq!(round(-2.4), -2);
    }
}
