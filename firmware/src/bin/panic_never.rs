//! Panic-freedom at link time: the kernel alone, driven through its whole
//! public runtime API with inputs the optimiser cannot see (synthetic
//! frames, requests and limits through `core::hint::black_box`), and a
//! panic handler that calls a symbol no object defines.
//!
//! After optimisation (release: fat LTO, one codegen unit) the handler is
//! linked only if some panic path — an index out of bounds, an `unwrap`,
//! a slice or arithmetic check — is still reachable from `Kernel::new_in`,
//! `request`, `step`, `update_limits`, `pop_event` or the state accessors.
//! The link then fails naming the undefined symbol and the function that
//! refers to it; a successful link proves no panic path survives in code
//! reachable from that API (the approach of the `no-panic` and
//! `panic-never` crates). The plant is not linked: this checks the kernel,
//! not the simulation around it.
//!
//! Build: `cargo build --release --bin panic-never` in `firmware/`. Running
//! it is not the point (it loops on whatever the inputs are). With
//! `--features panic-canary` one deliberate out-of-bounds index is added
//! and the link must fail: the check is live.

#![no_std]
#![no_main]

use core::hint::black_box;
use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;
use cortex_m_rt::entry;
use limb_kernel::arm::JointAngles;
use limb_kernel::geometry::{Pose, Wrench};
use limb_kernel::{Kernel, KernelConfig, PathSample, Request};

/// The kernel, built in place.
static mut KERNEL: MaybeUninit<Kernel> = MaybeUninit::uninit();

/// A number the optimiser cannot predict.
fn any() -> f64 {
    black_box(0.0)
}

/// A request the optimiser cannot predict, or none.
fn any_request() -> Option<Request> {
    match black_box(0u8) {
        0 => Some(Request::StartEstimation),
        1 => Some(Request::ApproveManipulation(JointAngles {
            shoulder_elevation: any(),
            elbow_flexion: any(),
        })),
        2 => Some(Request::FinishManipulation),
        3 => Some(Request::Stop),
        4 => Some(Request::Reset),
        _ => None,
    }
}

#[entry]
fn main() -> ! {
    // SAFETY: main runs once; this is the only reference to KERNEL.
    let slot = unsafe { &mut *addr_of_mut!(KERNEL) };
    let Ok(kernel) = Kernel::new_in(slot, black_box(KernelConfig::default())) else {
        loop {
            cortex_m::asm::nop();
        }
    };
    loop {
        let frame = PathSample {
            time: any(),
            pose: Pose::new(any(), any(), any()),
            wrench: Wrench::new(any(), any(), any()),
        };
        if let Some(request) = any_request() {
            let _ = black_box(kernel.request(request, any()));
        }
        black_box(kernel.step(Some(&frame), any()));
        while let Some(event) = kernel.pop_event() {
            black_box(event);
        }
        if black_box(false) {
            let _ = black_box(kernel.update_limits(black_box(kernel.config().limits)));
        }
        black_box(kernel.state().arm());
        black_box(kernel.path().len());
        black_box(kernel.dropped_events());
        #[cfg(feature = "panic-canary")]
        black_box(kernel.path()[black_box(usize::MAX)]);
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    extern "Rust" {
        /// Defined nowhere: referring to it fails the link.
        fn limb_kernel_has_a_reachable_panic_path() -> !;
    }
    // SAFETY: never called at run time; the link fails if this is reachable.
    unsafe { limb_kernel_has_a_reachable_panic_path() }
}
