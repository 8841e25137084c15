//! REQ-MEM-001: the kernel's whole state is one value of bounded size.

use limb_kernel::Kernel;

/// REQ-MEM-001: a Kernel (state, grasp-path buffer, rate window, trace)
/// fits in 256 KiB, so a target can place it in a static.
#[test]
fn req_mem_001_kernel_state_is_bounded() {
    let size = core::mem::size_of::<Kernel>();
    println!("size_of::<Kernel>() = {size} bytes");
    assert!(size <= 256 * 1024, "Kernel is {size} bytes");
}
