//! Contracts of the libm functions the kernel calls, and the Kani stubs
//! that replace them in proofs.
//!
//! # Why stubs
//! Square roots and trigonometry bit-blasted through CBMC make a whole
//! `step` intractable (issue 21: harnesses ran out of memory or time with
//! libm's software floats). A harness therefore replaces each function by
//! a stub that returns *any* value its contract allows
//! (`#[kani::stub(libm::hypot, crate::kani_stubs::hypot)]`). A property
//! proved with the stubs holds for every implementation that meets the
//! contracts, the real libm included, so the stubs are sound exactly when
//! libm meets them: that is the proptest property [`tests`] checks against
//! the real functions (edge values, NaN and infinities included).
//!
//! # Contracts (IEEE-754 binary64)
//! | function | NaN / ∞ | finite input |
//! |---|---|---|
//! | `sqrt(x)` | NaN for NaN or x < 0, +∞ for +∞ | ±0 → itself; `min(x, 1) ≤ r ≤ max(x, 1)` |
//! | `hypot(x, y)` | +∞ if either is ±∞, else NaN if either is NaN | `max(|x|, |y|) ≤ r ≤ |x| + |y|`, exact when one is 0 |
//! | `sin(x)`, `cos(x)` | NaN for NaN or ±∞ | `−1 ≤ r ≤ 1`; sin(±0) = ±0, cos(±0) = 1 |
//! | `atan2(y, x)` | NaN if either is NaN | `−π ≤ r ≤ π` (π rounded); 0 for y = +0, x > 0 |
//! | `acos(x)` | NaN for NaN or |x| > 1 | `0 ≤ r ≤ π` |
//!
//! The stubs are what the proofs may assume of the real functions: they
//! carry no more (no monotonicity, no accuracy), so numerical agreement
//! (e.g. the joint-limit verdict against an independent model) stays a
//! proptest property, not a proof.

use core::f64::consts::PI;

/// A harness with the stubs of the libm functions named in brackets, each
/// replaced by its contract's stub in [`stub`]: one line instead of one
/// attribute per function on every harness. The stubs apply only under
/// `cargo kani` (`cfg(kani)`); under `cargo test` the harness is the
/// plain function the sampling stand-in runs.
///
/// ```ignore
/// libm_stubbed! { [hypot, atan2]
///     /// REQ-…: what the harness proves.
///     #[cfg_attr(kani, kani::proof)]
///     fn harness() { … }
/// }
/// ```
macro_rules! libm_stubbed {
    ([$($f:ident),+] $(#[$attr:meta])* $vis:vis fn $name:ident() $body:block) => {
        $(#[$attr])*
        $(#[cfg_attr(kani, kani::stub(libm::$f, crate::kani_stubs::stub::$f))])+
        $vis fn $name() $body
    };
}
pub(crate) use libm_stubbed;

/// The contract of `sqrt`: may `r` be `libm::sqrt(x)`?
pub(crate) fn sqrt_contract(x: f64, r: f64) -> bool {
    if x.is_nan() || x < 0.0 {
        r.is_nan()
    } else if x == f64::INFINITY {
        r == f64::INFINITY
    } else if x == 0.0 {
        r.to_bits() == x.to_bits()
    } else {
        r.is_finite() && x.min(1.0) <= r && r <= x.max(1.0)
    }
}

/// The contract of `hypot`: may `r` be `libm::hypot(x, y)`?
pub(crate) fn hypot_contract(x: f64, y: f64, r: f64) -> bool {
    let (ax, ay) = (libm::fabs(x), libm::fabs(y));
    if ax == f64::INFINITY || ay == f64::INFINITY {
        r == f64::INFINITY
    } else if x.is_nan() || y.is_nan() {
        r.is_nan()
    } else if ay == 0.0 {
        r == ax
    } else if ax == 0.0 {
        r == ay
    } else {
        ax.max(ay) <= r && r <= ax + ay
    }
}

/// The contract of `sin` (`sine`) and `cos`: may `r` be the function of
/// `x`, whose value at ±0 is `at_zero(x)`?
fn bounded_trig_contract(x: f64, r: f64, at_zero: f64) -> bool {
    if !x.is_finite() {
        r.is_nan()
    } else if x == 0.0 {
        r.to_bits() == at_zero.to_bits()
    } else {
        (-1.0..=1.0).contains(&r)
    }
}

/// The contract of `sin`: may `r` be `libm::sin(x)`?
pub(crate) fn sin_contract(x: f64, r: f64) -> bool {
    bounded_trig_contract(x, r, x)
}

/// The contract of `cos`: may `r` be `libm::cos(x)`?
pub(crate) fn cos_contract(x: f64, r: f64) -> bool {
    bounded_trig_contract(x, r, 1.0)
}

/// The contract of `atan2`: may `r` be `libm::atan2(y, x)`?
pub(crate) fn atan2_contract(y: f64, x: f64, r: f64) -> bool {
    if x.is_nan() || y.is_nan() {
        r.is_nan()
    } else if y.to_bits() == 0 && x > 0.0 {
        r.to_bits() == 0
    } else {
        (-PI..=PI).contains(&r)
    }
}

/// The contract of `acos`: may `r` be `libm::acos(x)`?
pub(crate) fn acos_contract(x: f64, r: f64) -> bool {
    if x.is_nan() || !(-1.0..=1.0).contains(&x) {
        r.is_nan()
    } else {
        (0.0..=PI).contains(&r)
    }
}

/// Kani stubs: any value the contract allows. Where the contract allows
/// one value only (hypot with a leg 0, the sine and cosine of 0, the root
/// of 0 or +∞, the angle of +0 over a positive x), the stub returns it
/// outright rather than as an assumed `any`: the same values, but a
/// constant input then gives a constant that symbolic execution folds
/// (an assumed value is a symbol to it, and every branch on it stays), so
/// a harness's fixed setup (the fixed arm's validation, a move along an
/// axis) is built to numbers, not to formulas.
#[cfg(kani)]
pub(crate) mod stub {
    use super::*;

    /// Stub of `libm::sqrt`.
    pub(crate) fn sqrt(x: f64) -> f64 {
        if x == 0.0 || x == f64::INFINITY {
            return x;
        }
        let r: f64 = kani::any();
        kani::assume(sqrt_contract(x, r));
        r
    }

    /// Stub of `libm::hypot`.
    pub(crate) fn hypot(x: f64, y: f64) -> f64 {
        if y == 0.0 && !x.is_nan() {
            return libm::fabs(x);
        }
        if x == 0.0 && !y.is_nan() {
            return libm::fabs(y);
        }
        let r: f64 = kani::any();
        kani::assume(hypot_contract(x, y, r));
        r
    }

    /// Stub of `libm::sin`.
    pub(crate) fn sin(x: f64) -> f64 {
        if x == 0.0 {
            return x;
        }
        let r: f64 = kani::any();
        kani::assume(sin_contract(x, r));
        r
    }

    /// Stub of `libm::cos`.
    pub(crate) fn cos(x: f64) -> f64 {
        if x == 0.0 {
            return 1.0;
        }
        let r: f64 = kani::any();
        kani::assume(cos_contract(x, r));
        r
    }

    /// Stub of `libm::atan2`.
    pub(crate) fn atan2(y: f64, x: f64) -> f64 {
        if y.to_bits() == 0 && x > 0.0 {
            return 0.0;
        }
        let r: f64 = kani::any();
        kani::assume(atan2_contract(y, x, r));
        r
    }

    /// Stub of `libm::acos`.
    pub(crate) fn acos(x: f64) -> f64 {
        let r: f64 = kani::any();
        kani::assume(acos_contract(x, r));
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Edge values and every other bit pattern: each stub's contract must
    /// hold for the real libm function.
    static EDGES: [f64; 19] = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        0.5,
        -0.5,
        PI,
        -PI,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::MIN_POSITIVE,
        -f64::MIN_POSITIVE,
        f64::MAX,
        f64::MIN,
        f64::EPSILON,
        5e-324,
        1e300,
        1e-300,
    ];

    fn any_f64() -> impl Strategy<Value = f64> {
        prop_oneof![
            prop::sample::select(&EDGES[..]),
            any::<u64>().prop_map(f64::from_bits),
            -10.0..10.0f64,
            -1.0..1.0f64,
            -1e6..1e6f64,
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]

        #[test]
        fn libm_meets_the_stub_contracts(x in any_f64(), y in any_f64()) {
            prop_assert!(sqrt_contract(x, libm::sqrt(x)), "sqrt({x:e}) = {:e}", libm::sqrt(x));
            prop_assert!(hypot_contract(x, y, libm::hypot(x, y)),
                "hypot({x:e}, {y:e}) = {:e}", libm::hypot(x, y));
            prop_assert!(sin_contract(x, libm::sin(x)), "sin({x:e}) = {:e}", libm::sin(x));
            prop_assert!(cos_contract(x, libm::cos(x)), "cos({x:e}) = {:e}", libm::cos(x));
            prop_assert!(atan2_contract(y, x, libm::atan2(y, x)),
                "atan2({y:e}, {x:e}) = {:e}", libm::atan2(y, x));
            prop_assert!(acos_contract(x, libm::acos(x)), "acos({x:e}) = {:e}", libm::acos(x));
        }
    }

    /// The contracts are not vacuous: each rejects a wrong answer.
    #[test]
    fn contracts_reject_wrong_values() {
        assert!(!sqrt_contract(4.0, 5.0) && !sqrt_contract(-1.0, 0.0));
        assert!(!hypot_contract(3.0, 4.0, 2.0) && !hypot_contract(3.0, 4.0, 8.0));
        assert!(!hypot_contract(f64::NAN, f64::INFINITY, f64::NAN));
        assert!(!sin_contract(1.0, 1.5) && !sin_contract(f64::INFINITY, 0.0));
        assert!(!cos_contract(0.0, 0.5) && !atan2_contract(0.0, 1.0, 0.1));
        assert!(!acos_contract(2.0, 0.0) && !acos_contract(0.5, -0.1));
    }
}
