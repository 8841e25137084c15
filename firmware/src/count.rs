//! Counting instructions on QEMU with the SysTick.
//!
//! # Theory of operation
//! QEMU models no DWT cycle counter (CYCCNT reads 0 on `mps2-an500`), but
//! it does model the SysTick, clocked from the board's system clock in
//! QEMU's virtual time. Under `-icount shift=0` virtual time advances
//! exactly 1 ns per executed instruction, so the SysTick, counting at
//! the system clock, counts instructions in fixed units: at 25 MHz one tick
//! is 40 instructions. [`calibrate`] measures the units with a loop of a
//! known instruction count instead of trusting the board's frequency.
//!
//! The SysTick is a 24-bit down-counter; its exception counts the wraps,
//! so [`now`] is a 64-bit tick count (a step of up to 2⁶⁴ ticks).

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::{SCB, SYST};

/// The SysTick's reload value: the full 24 bits.
const RELOAD: u32 = 0x00FF_FFFF;

/// SysTick wraps so far (incremented by the SysTick exception).
static WRAPS: AtomicU32 = AtomicU32::new(0);

/// Counts one SysTick wrap. Called by the SysTick exception handler only.
pub fn on_wrap() {
    WRAPS.fetch_add(1, Ordering::Relaxed);
}

/// Starts the SysTick on the processor clock, full range, with its wrap
/// exception enabled, and waits for its first reload.
pub fn start(mut syst: SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(RELOAD);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
    // The cleared counter reads 0 until its first reload.
    while SYST::get_current() == 0 {}
}

/// Ticks since [`start`].
///
/// The counter reloads before its exception is taken (QEMU takes
/// interrupts between translated blocks), so a read can find it reloaded
/// with the wrap not yet counted: the exception is then pending, and a
/// count read near the top (reloaded, not about to wrap) adds that wrap.
/// Without it a step that began just before a wrap and ended just after
/// read as 2⁶⁴ − n ticks (seen: one Estimate step of the firmware
/// session at u32::MAX instructions).
#[inline(always)]
pub fn now() -> u64 {
    loop {
        let before = WRAPS.load(Ordering::Relaxed);
        let current = SYST::get_current();
        let pending = SCB::is_pendst_pending() && current > RELOAD / 2;
        if WRAPS.load(Ordering::Relaxed) == before {
            let wraps = u64::from(before) + u64::from(pending);
            return wraps * u64::from(RELOAD + 1) + u64::from(RELOAD - current);
        }
    }
}

/// Executed instructions per SysTick tick, and the ticks an empty
/// measurement (two [`now`] calls back to back) reads.
#[derive(Clone, Copy, Debug)]
pub struct Calibration {
    /// Instructions per tick (40 on QEMU's 25 MHz `mps2-an500` under
    /// `-icount shift=0`).
    pub instructions_per_tick: u64,
    /// Ticks read by an empty measurement (the measurement's own cost).
    pub overhead_ticks: u64,
}

/// Iterations of the calibration loop (two instructions each).
const LOOP: u32 = 4_000_000;

/// Measures the tick's worth in instructions with a loop of a known
/// instruction count (`subs` + `bne`, 2 × [`LOOP`]).
pub fn calibrate() -> Calibration {
    let start = now();
    // SAFETY: a register-only countdown loop. Not `nomem`: the compiler
    // must not move the SysTick reads across it.
    unsafe {
        core::arch::asm!(
            "2:",
            "subs {n}, {n}, #1",
            "bne 2b",
            n = inout(reg) LOOP => _,
            options(nostack),
        );
    }
    let ticks = now() - start;
    let empty = {
        let a = now();
        now() - a
    };
    Calibration {
        instructions_per_tick: (2 * u64::from(LOOP) + ticks / 2) / ticks.max(1),
        overhead_ticks: empty,
    }
}
