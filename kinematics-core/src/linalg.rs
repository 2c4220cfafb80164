//! The 6x6 linear algebra of the kinematics: LU factorisation with partial pivoting, solves
//! with a matrix and its transpose, the inverse and the condition number. `f32`, no
//! allocation; arithmetic through [`Math`] (the boot ROM's routines on the RP2040).
//!
//! A near-singular matrix is refused (an error), never divided by: a pivot is accepted only if
//! it is larger than [`PIVOT_TOLERANCE`] times the largest entry of its column in the matrix
//! factored, which also makes the test blind to the units of the columns (mm or rad).

// Index loops read like the textbook algorithms they are.
#![allow(clippy::needless_range_loop)]

use crate::error::KinematicsError;
use crate::math::{abs_bits, Math, Real};

/// A 6x6 matrix (`f32`): Jacobians, stiffness and compliance.
pub type Mat6 = nalgebra::Matrix6<f32>;
/// A 6-vector (`f32`): a twist, a wrench, six joint values.
pub type Vec6 = nalgebra::Vector6<f32>;

/// Smallest pivot accepted, relative to the largest entry of its column: about 16 times the
/// `f32` rounding of each of the six terms of an elimination step. A matrix refused by it has a
/// condition number of the order of 1e6 or more, where an `f32` solution would have no correct
/// digits left.
pub const PIVOT_TOLERANCE: f32 = 1e-6;

/// `P A = L U` of a 6x6 matrix `A`, `L` unit lower triangular, `U` upper triangular, `P` a row
/// permutation (partial pivoting).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lu6 {
    /// `L` below the diagonal, `U` on and above it, row-major, rows in pivot order.
    lu: [[f32; 6]; 6],
    /// `1 / U_kk`.
    inv_pivot: [f32; 6],
    /// Row `i` of `L U` is row `perm[i]` of `A`.
    perm: [u8; 6],
}

impl Lu6 {
    /// Factors `a`; refused ([`KinematicsError::Singular`]) if a pivot is not larger than
    /// [`PIVOT_TOLERANCE`] times its column's largest entry (or not finite).
    pub fn factor<M: Math>(a: &Mat6) -> Result<Lu6, KinematicsError> {
        let r = Real::<M>::new;
        let mut lu = [[0.0f32; 6]; 6];
        let mut scale = [0u32; 6];
        for (i, row) in lu.iter_mut().enumerate() {
            for (k, v) in row.iter_mut().enumerate() {
                *v = a[(i, k)];
                scale[k] = scale[k].max(abs_bits(*v));
            }
        }
        let mut perm = [0u8, 1, 2, 3, 4, 5];
        let mut inv_pivot = [0.0f32; 6];
        for k in 0..6 {
            let best = (k..6).max_by_key(|&i| abs_bits(lu[i][k])).unwrap_or(k);
            lu.swap(k, best);
            perm.swap(k, best);
            let pivot = lu[k][k];
            check_pivot::<M>(pivot, scale[k])?;
            inv_pivot[k] = 1.0 / pivot;
            for i in k + 1..6 {
                let factor = r(lu[i][k]) * r(inv_pivot[k]);
                lu[i][k] = factor.0;
                for j in k + 1..6 {
                    lu[i][j] = (r(lu[i][j]) - factor * r(lu[k][j])).0;
                }
            }
        }
        Ok(Lu6 {
            lu,
            inv_pivot,
            perm,
        })
    }

    /// `x` with `A x = b`.
    pub fn solve<M: Math>(&self, b: &Vec6) -> Vec6 {
        let r = Real::<M>::new;
        let mut y = [0.0f32; 6];
        for i in 0..6 {
            let mut sum = r(b[usize::from(self.perm[i])]);
            for (j, yj) in y.iter().enumerate().take(i) {
                sum = sum - r(self.lu[i][j]) * r(*yj);
            }
            y[i] = sum.0;
        }
        for i in (0..6).rev() {
            let mut sum = r(y[i]);
            for (j, yj) in y.iter().enumerate().skip(i + 1) {
                sum = sum - r(self.lu[i][j]) * r(*yj);
            }
            y[i] = (sum * r(self.inv_pivot[i])).0;
        }
        Vec6::from(y)
    }

    /// `x` with `A^T x = b`: `U^T w = b`, then `L^T y = w`, then `x = P^T y`.
    pub fn solve_transposed<M: Math>(&self, b: &Vec6) -> Vec6 {
        let r = Real::<M>::new;
        let mut w = [0.0f32; 6];
        for k in 0..6 {
            let mut sum = r(b[k]);
            for (j, wj) in w.iter().enumerate().take(k) {
                sum = sum - r(self.lu[j][k]) * r(*wj);
            }
            w[k] = (sum * r(self.inv_pivot[k])).0;
        }
        for k in (0..6).rev() {
            let mut sum = r(w[k]);
            for j in k + 1..6 {
                sum = sum - r(self.lu[j][k]) * r(w[j]);
            }
            w[k] = sum.0;
        }
        let mut x = Vec6::zeros();
        for (i, wi) in w.iter().enumerate() {
            x[usize::from(self.perm[i])] = *wi;
        }
        x
    }

    /// `A^-1`, column by column.
    pub fn inverse<M: Math>(&self) -> Mat6 {
        let mut inv = Mat6::zeros();
        for k in 0..6 {
            let mut e = Vec6::zeros();
            e[k] = 1.0;
            inv.set_column(k, &self.solve::<M>(&e));
        }
        inv
    }
}

/// Whether a pivot may be divided by: finite, and larger than [`PIVOT_TOLERANCE`] times the
/// largest magnitude of its column (`column_bits`, an `f32`'s bits), tested as
/// `|pivot| > PIVOT_TOLERANCE * column` with one multiplication and integer comparisons
/// (non-negative floats order like their bits; a division and a float comparison are library
/// calls on the RP2040). Refused ([`KinematicsError::Singular`], with the ratio) otherwise,
/// NaN and a zero column included.
fn check_pivot<M: Math>(pivot: f32, column_bits: u32) -> Result<(), KinematicsError> {
    const INFINITY: u32 = 0x7f80_0000;
    let magnitude = abs_bits(pivot);
    if column_bits != 0 && column_bits < INFINITY && magnitude < INFINITY {
        let bound = M::mul(PIVOT_TOLERANCE, f32::from_bits(column_bits));
        if magnitude > bound.to_bits() {
            return Ok(());
        }
    }
    let column = f32::from_bits(column_bits);
    let ratio = if column > 0.0 {
        pivot.abs() / column
    } else {
        0.0
    };
    Err(KinematicsError::Singular {
        pivot_ratio: if ratio.is_finite() { ratio } else { 0.0 },
    })
}

/// The 1-norm of a matrix: its largest column sum of absolute values.
pub fn norm1(m: &Mat6) -> f32 {
    m.column_iter()
        .map(|c| c.iter().map(|v| v.abs()).sum::<f32>())
        .fold(0.0, f32::max)
}

/// The condition number `||A||_1 ||A^-1||_1`; infinite if `A` is refused by [`Lu6::factor`].
/// Units matter: scale the columns to comparable units first (see
/// [`crate::jacobian::Jacobian::condition_number`]).
pub fn condition_number<M: Math>(a: &Mat6) -> f32 {
    match Lu6::factor::<M>(a) {
        Ok(lu) => {
            let k = norm1(a) * norm1(&lu.inverse::<M>());
            if k.is_finite() {
                k
            } else {
                f32::INFINITY
            }
        }
        Err(_) => f32::INFINITY,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;
    use crate::test_support::xorshift;

    fn random(seed: &mut u32) -> Mat6 {
        Mat6::from_fn(|_, _| (xorshift(seed) as f32 / u32::MAX as f32) * 2.0 - 1.0)
    }

    #[test]
    fn solves_and_inverts_random_matrices() {
        let mut seed = 0x2468_ace1;
        for _ in 0..200 {
            let a = random(&mut seed);
            let b = random(&mut seed).column(0).into_owned();
            let Ok(lu) = Lu6::factor::<Libm>(&a) else {
                continue;
            };
            let k = condition_number::<Libm>(&a);
            let tol = 1e-5 * k.max(1.0);
            let x = lu.solve::<Libm>(&b);
            assert!((a * x - b).amax() < tol, "{k}");
            let y = lu.solve_transposed::<Libm>(&b);
            assert!((a.transpose() * y - b).amax() < tol, "{k}");
            let inv = lu.inverse::<Libm>();
            assert!((a * inv - Mat6::identity()).amax() < tol, "{k}");
        }
    }

    #[test]
    fn singular_matrices_are_refused_not_divided_by() {
        let mut a = Mat6::identity();
        a[(4, 4)] = 0.0;
        assert!(matches!(
            Lu6::factor::<Libm>(&a),
            Err(KinematicsError::Singular { pivot_ratio }) if pivot_ratio == 0.0
        ));
        assert_eq!(condition_number::<Libm>(&a), f32::INFINITY);
        // Two equal rows, scaled: rank 5.
        let mut seed = 7;
        let mut b = random(&mut seed);
        let row = b.row(1) * 3.0;
        b.set_row(4, &row);
        assert!(Lu6::factor::<Libm>(&b).is_err());
        let mut c = Mat6::identity();
        c[(2, 3)] = f32::NAN;
        c[(2, 2)] = f32::NAN;
        assert!(Lu6::factor::<Libm>(&c).is_err());
        assert!(Lu6::factor::<Libm>(&Mat6::zeros()).is_err());
        // A pivot just above the tolerance (of its column's largest entry, 1) is taken, one
        // just below it is not.
        let mut d = Mat6::identity();
        d[(0, 5)] = 1.0;
        d[(5, 5)] = 2e-6;
        assert!(Lu6::factor::<Libm>(&d).is_ok());
        d[(5, 5)] = 0.5e-6;
        assert!(matches!(
            Lu6::factor::<Libm>(&d),
            Err(KinematicsError::Singular { pivot_ratio }) if pivot_ratio == 0.5e-6
        ));
    }
}
