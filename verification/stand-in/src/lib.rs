//! A small stand-in for the `kani` API, so the proof harnesses beside the
//! kernel's modules (`#[cfg(any(test, kani))] mod verification`) type-check
//! and run under `cargo test` where the Kani verifier is not installed.
//! A harness module imports it as `kani` when `cfg(kani)` is off; under
//! `cargo kani` the real `kani` crate is used and the same harnesses are
//! proved, not sampled. Kani's stubs (`#[kani::stub]`) are not applied
//! here: the stand-in runs the real functions, whose agreement with each
//! stub's contract is a proptest property (`kernel/src/kani_stubs.rs`).
//!
//! * [`any`] draws a value from a seeded generator that favours edge cases
//!   (zero, ±0, NaN, ±∞, tiny and huge magnitudes, small integers).
//! * [`assume`] rejects the current draw: it unwinds with a marker that
//!   [`run`] catches and counts, like Kani discarding the path.
//! * [`cover!`] records that a condition was reached; [`run`]
//!   fails a harness whose covers were never hit, as Kani reports an
//!   unsatisfiable cover.
//!
//! Sampling is not proof: the stand-in finds counterexamples, it cannot
//! show their absence. The requirement index says which harnesses have
//! been run under real Kani.

use std::cell::{Cell, RefCell};
use std::collections::BTreeMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Once;

thread_local! {
    static STATE: Cell<u64> = const { Cell::new(0x9E37_79B9_7F4A_7C15) };
    static COVERS: RefCell<BTreeMap<&'static str, u64>> = const { RefCell::new(BTreeMap::new()) };
}

/// The unwinding payload of a rejected draw.
struct Rejected;

fn next() -> u64 {
    STATE.with(|s| {
        // xorshift64*: deterministic for a given seed.
        let mut x = s.get();
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        s.set(x);
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    })
}

/// Values [`any`] can produce.
pub trait Arbitrary {
    /// One draw.
    fn any() -> Self;
}

impl Arbitrary for bool {
    fn any() -> Self {
        next() & 1 == 1
    }
}

impl Arbitrary for u8 {
    fn any() -> Self {
        (next() >> 56) as u8
    }
}

impl Arbitrary for u32 {
    fn any() -> Self {
        match next() % 4 {
            0 => (next() % 8) as u32,
            1 => u32::MAX - (next() % 8) as u32,
            _ => (next() >> 32) as u32,
        }
    }
}

impl Arbitrary for f64 {
    fn any() -> Self {
        const EDGES: [f64; 10] = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::EPSILON,
        ];
        let r = next();
        match r % 8 {
            0 => EDGES[(next() % EDGES.len() as u64) as usize],
            1 => f64::from_bits(next()),
            2 => (next() as f64 / u64::MAX as f64 - 0.5) * 2000.0,
            _ => (next() as f64 / u64::MAX as f64 - 0.5) * 4.0,
        }
    }
}

/// An arbitrary value.
pub fn any<T: Arbitrary>() -> T {
    T::any()
}

/// Discards the current draw unless `condition` holds.
pub fn assume(condition: bool) {
    if !condition {
        std::panic::resume_unwind(Box::new(Rejected));
    }
}

/// Records that `name`'s condition was reached (see [`cover!`]).
pub fn record_cover(name: &'static str, hit: bool) {
    COVERS.with(|c| *c.borrow_mut().entry(name).or_insert(0) += u64::from(hit));
}

/// `kani::cover!(condition, "message")`: the stand-in counts hits.
#[macro_export]
macro_rules! cover {
    ($condition:expr, $message:literal) => {
        $crate::record_cover($message, $condition)
    };
}

/// Outcome of running one harness under the stand-in.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Run {
    /// Draws that reached the end of the harness.
    pub accepted: u64,
    /// Draws discarded by `assume`.
    pub rejected: u64,
    /// Covers that were never hit.
    pub unreached: Vec<&'static str>,
}

/// Installs, once per process, a panic hook that stays silent for rejected
/// draws and reports every other panic as the default hook does.
fn quiet_rejections() {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !info.payload().is::<Rejected>() {
                default(info);
            }
        }));
    });
}

/// Runs `harness` `draws` times from `seed`. A failed assertion inside the
/// harness propagates as a panic (the test fails with it).
pub fn run(seed: u64, draws: u64, harness: fn()) -> Run {
    STATE.with(|s| s.set(seed | 1));
    COVERS.with(|c| c.borrow_mut().clear());
    quiet_rejections();
    let (mut accepted, mut rejected) = (0, 0);
    for _ in 0..draws {
        match catch_unwind(AssertUnwindSafe(harness)) {
            Ok(()) => accepted += 1,
            Err(payload) if payload.is::<Rejected>() => rejected += 1,
            Err(payload) => std::panic::resume_unwind(payload),
        }
    }
    let unreached = COVERS.with(|c| {
        c.borrow()
            .iter()
            .filter(|(_, hits)| **hits == 0)
            .map(|(name, _)| *name)
            .collect()
    });
    Run {
        accepted,
        rejected,
        unreached,
    }
}

/// Runs `harness` `draws` times from a seed derived from `draws` and
/// panics, naming `name`, unless most draws were accepted and every
/// `cover!` was reached (Kani's "unsatisfiable cover" is a failure here).
pub fn check(name: &str, draws: u64, harness: fn()) -> Run {
    let outcome = run(0x5EED ^ draws, draws, harness);
    assert!(
        outcome.accepted * 2 > draws,
        "{name}: too many draws rejected: {outcome:?}"
    );
    assert!(
        outcome.unreached.is_empty(),
        "{name}: covers never reached: {:?}",
        outcome.unreached
    );
    outcome
}
