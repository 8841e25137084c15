//! Small dense linear systems A x = b without a panic path.
//!
//! # Theory of operation
//! LU decomposition with partial pivoting, then forward and back
//! substitution: the same operations, in the same order, as nalgebra's
//! `LU::new` followed by `LU::solve` (first largest |pivot|, a zero pivot
//! column skipped, multipliers scaled by the pivot's reciprocal, `None`
//! for a zero on U's diagonal), so results are bit-identical to nalgebra's
//! (property-tested below). nalgebra's version keeps index assertions
//! the compiler cannot remove (`swap_rows`, row views, the permutation
//! sequence), which the firmware's panic-never link check finds; here
//! every index runs over a fixed-size array's own range.
//!
//! Work is O(N³) with N a compile-time constant; no allocation, no
//! recursion.

/// Solves `a x = b` for `x`, `a` given row by row (`a[row][column]`).
/// `None` when the system is singular (a zero on U's diagonal); a system
/// with non-finite entries gives non-finite `x` or `None`, never a panic.
pub(crate) fn solve<const N: usize>(mut a: [[f64; N]; N], mut b: [f64; N]) -> Option<[f64; N]> {
    // pivots[i]: the row swapped with row i at step i (i itself: none).
    let mut pivots = [0usize; N];
    for (i, pivot) in pivots.iter_mut().enumerate() {
        *pivot = i;
        let mut largest = column_abs(&a, i, i);
        for r in i + 1..N {
            let value = column_abs(&a, r, i);
            if value > largest {
                largest = value;
                *pivot = r;
            }
        }
        let p = *pivot;
        let diag = element(&a, p, i);
        if diag == 0.0 {
            continue;
        }
        if p != i {
            // Columns 0..=i, then each later column, trade rows i and p.
            for c in 0..=i {
                swap_rows(&mut a, i, p, c);
            }
        }
        let inverse = 1.0 / diag;
        for row in a.iter_mut().skip(i + 1) {
            row[i] *= inverse;
        }
        for k in i + 1..N {
            if p != i {
                swap_rows(&mut a, i, p, k);
            }
            let factor = -element(&a, i, k);
            for row in a.iter_mut().skip(i + 1) {
                row[k] += factor * row[i];
            }
        }
    }
    for (i, &p) in pivots.iter().enumerate() {
        if p != i && p < N {
            b.swap(i, p);
        }
    }
    // L has a unit diagonal.
    for i in 0..N {
        let coefficient = -b[i];
        for (r, row) in a.iter().enumerate().skip(i + 1) {
            b[r] += coefficient * row[i];
        }
    }
    for i in (0..N).rev() {
        let diag = element(&a, i, i);
        if diag == 0.0 {
            return None;
        }
        let coefficient = b[i] / diag;
        b[i] = coefficient;
        for (r, row) in a.iter().enumerate().take(i) {
            b[r] -= coefficient * row[i];
        }
    }
    Some(b)
}

/// `a[row][column]`, NaN outside the matrix (never reached: callers index
/// within 0..N).
fn element<const N: usize>(a: &[[f64; N]; N], row: usize, column: usize) -> f64 {
    a.get(row)
        .and_then(|r| r.get(column))
        .copied()
        .unwrap_or(f64::NAN)
}

/// |a[row][column]| (NaN outside the matrix, as [`element`]).
fn column_abs<const N: usize>(a: &[[f64; N]; N], row: usize, column: usize) -> f64 {
    libm::fabs(element(a, row, column))
}

/// Swaps `a[i][column]` and `a[p][column]` (nothing outside the matrix).
fn swap_rows<const N: usize>(a: &mut [[f64; N]; N], i: usize, p: usize, column: usize) {
    let (x, y) = (element(a, i, column), element(a, p, column));
    if let Some(v) = a.get_mut(i).and_then(|r| r.get_mut(column)) {
        *v = y;
    }
    if let Some(v) = a.get_mut(p).and_then(|r| r.get_mut(column)) {
        *v = x;
    }
}

#[cfg(test)]
mod tests {
    use super::solve;
    use nalgebra::{SMatrix, SVector};
    use proptest::prelude::*;

    /// nalgebra's answer, as arrays (a macro: nalgebra's LU needs a
    /// concrete size).
    macro_rules! nalgebra {
        ($n:literal, $a:expr, $b:expr) => {{
            let (a, b): ([[f64; $n]; $n], [f64; $n]) = ($a, $b);
            let m = SMatrix::<f64, $n, $n>::from_fn(|r, c| a[r][c]);
            let v = SVector::<f64, $n>::from_fn(|r, _| b[r]);
            m.lu()
                .solve(&v)
                .map(|x| core::array::from_fn::<f64, $n, _>(|r| x[r]))
        }};
    }

    fn bits<const N: usize>(x: Option<[f64; N]>) -> Option<[u64; N]> {
        x.map(|x| x.map(f64::to_bits))
    }

    /// Entries drawn from a few exact values (zeros and repeats make
    /// singular and tied-pivot systems common), or any finite number.
    fn entry() -> impl Strategy<Value = f64> {
        prop_oneof![
            prop::sample::select(&[0.0, 1.0, -1.0, 2.0, 0.5, -3.0][..]),
            -1e3..1e3f64,
        ]
    }

    proptest! {
        #[test]
        fn bit_identical_to_nalgebra_3(a in prop::array::uniform3(prop::array::uniform3(entry())),
                                       b in prop::array::uniform3(entry())) {
            prop_assert_eq!(bits(solve(a, b)), bits(nalgebra!(3, a, b)));
        }

        /// REQ-DET-001: the panic-free solver gives nalgebra's bits, so the
        /// kernel computes the same numbers on host and target as before.
        #[test]
        fn bit_identical_to_nalgebra_7(a in prop::array::uniform7(prop::array::uniform7(entry())),
                                       b in prop::array::uniform7(entry())) {
            prop_assert_eq!(bits(solve(a, b)), bits(nalgebra!(7, a, b)));
        }
    }

    #[test]
    fn solves_and_refuses() {
        let x = solve([[2.0, 1.0], [1.0, 3.0]], [3.0, 5.0]).unwrap();
        assert!((x[0] - 0.8).abs() < 1e-15 && (x[1] - 1.4).abs() < 1e-15);
        assert_eq!(solve([[1.0, 2.0], [2.0, 4.0]], [1.0, 2.0]), None);
        let nan = solve([[f64::NAN, 0.0], [0.0, 1.0]], [1.0, 1.0]);
        assert!(nan.is_none_or(|x| x.iter().any(|v| v.is_nan())));
    }
}
