//! A pass-through shim of the `kani` API for `check.sh` (type checking
//! only: `any` returns a default value, `assume`, `assert` and `cover!` do
//! nothing).
pub use kani_macros::{proof, stub, unwind};
pub trait Arbitrary {
    fn any() -> Self;
}
macro_rules! arb { ($($t:ty),*) => { $(impl Arbitrary for $t { fn any() -> Self { Default::default() } })* } }
arb!(bool, u8, u16, u32, u64, usize, i32, i64, f32, f64);
pub fn any<T: Arbitrary>() -> T {
    T::any()
}
pub fn assume(_c: bool) {}
pub fn assert(_c: bool, _m: &'static str) {}
#[macro_export]
macro_rules! cover {
    ($c:expr, $m:literal) => {
        let _: bool = $c;
        let _: &str = $m;
    };
}
