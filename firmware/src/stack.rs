//! The stack's high-water mark: paint, run, read back.
//!
//! cortex-m-rt puts the stack at the top of RAM growing down towards the
//! end of `.bss` (`__sheap`; there is no heap). [`paint`] fills that gap
//! with a pattern up to a margin below the current stack pointer;
//! [`high_water`] finds the lowest word no longer holding the pattern. The
//! figure counts every byte the program's stack ever reached, from the
//! reset handler to the deepest call of the session; a word that happened
//! to be written with the pattern itself would make it low by at most that
//! word's depth (improbable; noted, not excluded).

use core::ptr::addr_of;

/// The paint.
const PAINT: u32 = 0xA5C3_5A3C;

/// Bytes below the current stack pointer left unpainted (the painting
/// function's own frame and its callee's).
const MARGIN: usize = 256;

extern "C" {
    /// End of `.bss` and `.uninit`: the lowest address the stack may reach.
    static __sheap: u32;
    /// Top of the stack (end of RAM).
    static _stack_start: u32;
}

fn bottom() -> usize {
    addr_of!(__sheap) as usize
}

fn top() -> usize {
    addr_of!(_stack_start) as usize
}

/// Paints the free stack: from the end of `.bss` to [`MARGIN`] bytes below
/// the stack pointer.
pub fn paint() {
    let sp = cortex_m::register::msp::read() as usize;
    let mut p = bottom();
    while p + MARGIN < sp {
        // SAFETY: [bottom, sp - MARGIN) is free stack below every live frame.
        unsafe { (p as *mut u32).write_volatile(PAINT) };
        p += 4;
    }
}

/// Bytes of stack used at the deepest point since [`paint`]: from the top
/// of RAM down to the lowest word that no longer holds the paint.
pub fn high_water() -> usize {
    let mut p = bottom();
    // SAFETY: reads of RAM between the end of .bss and the stack pointer.
    while p < top() && unsafe { (p as *const u32).read_volatile() } == PAINT {
        p += 4;
    }
    top() - p
}

/// Bytes between the end of `.bss` and the top of RAM: what the stack may
/// grow into.
pub fn capacity() -> usize {
    top() - bottom()
}
