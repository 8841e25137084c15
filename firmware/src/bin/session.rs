//! One whole kernel session on the target: grasp, estimate, validate,
//! manipulate, against the reference plant, through the same
//! `limb_session::run` loop as `limb run` on the host (and every robot
//! adapter).
//!
//! Prints (semihosting) the session's canonical digest — the event lines,
//! the exact model, the step counts and the command hash, the text of
//! `limb run --digest` — then the instructions of each kernel step per
//! state and the stack's high-water mark. Exits with failure when the
//! session did not complete or the stack outgrew [`STACK_BUDGET`].
//!
//! Run it with `cargo run --release --bin session` in `firmware/` (QEMU,
//! see `.cargo/config.toml`); `firmware/session.sh` compares it with the
//! host.

#![no_std]
#![no_main]

use core::alloc::{GlobalAlloc, Layout};
use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;
use cortex_m_rt::{entry, exception, ExceptionFrame};
use cortex_m_semihosting::{debug, hprintln};
use limb_firmware::{count, stack};
use limb_kernel::trace::TraceEvent;
use limb_kernel::{Command, Kernel, KernelConfig, StateKind};
use limb_session::digest::{Digest, EventLine};
use limb_session::{Frame, Observer, Operator, SessionPlan};
use limb_sim::robot::ReferenceRobot;
use limb_sim::{Plant, PlantParameters};

/// The firmware has no heap: every allocation fails, and a failed
/// allocation ends the run with failure. The plant crate links `alloc` for
/// its host-side texts; a nominal session allocates nothing, which this
/// allocator proves on every run.
struct NoHeap;

// SAFETY: returning null is GlobalAlloc's way to refuse an allocation.
unsafe impl GlobalAlloc for NoHeap {
    unsafe fn alloc(&self, _: Layout) -> *mut u8 {
        core::ptr::null_mut()
    }

    unsafe fn dealloc(&self, _: *mut u8, _: Layout) {}
}

#[global_allocator]
static HEAP: NoHeap = NoHeap;

/// The stack a whole session may use [bytes]: the check fails past it.
/// Measured 8 860 B (benchmarks/target.md): 12 KiB leaves 39 % for
/// growth, and a change that puts a kernel-sized value (235 kB) or a deep
/// recursion on the stack fails the check.
const STACK_BUDGET: usize = 12 * 1024;

/// The most instructions one kernel step may take, in any state: half of a
/// 1 ms period on a 600 MHz Cortex-M7 at one instruction per cycle
/// (REQ-TIME-002). Measured worst, soft-float: 245 120 (a refinement
/// slice of Estimate); the check fails past the budget.
const STEP_INSTRUCTION_BUDGET: u32 = 300_000;

/// The most kernel steps recorded (the default session takes about 33 000).
const CAPACITY: usize = 65_536;

/// The kernel, built in place (never on the stack).
static mut KERNEL: MaybeUninit<Kernel> = MaybeUninit::uninit();
/// Instructions of each step, in order.
static mut INSTRUCTIONS: [u32; CAPACITY] = [0; CAPACITY];
/// The state each step began in.
static mut STATES: [u8; CAPACITY] = [0; CAPACITY];
/// Scratch for sorting one state's counts.
static mut SCRATCH: [u32; CAPACITY] = [0; CAPACITY];

/// The states, in the order the cost table lists them.
const STATES_LISTED: [StateKind; 5] = [
    StateKind::Grasp,
    StateKind::Estimate,
    StateKind::Validated,
    StateKind::Manipulate,
    StateKind::SafeStop,
];

/// Counts each step's instructions and prints each event. The
/// instructions of a step are those between `before_step` and
/// `after_step`: `Kernel::step` and the two SysTick reads, less the
/// calibrated cost of an empty measurement.
struct Meter {
    instructions: &'static mut [u32; CAPACITY],
    states: &'static mut [u8; CAPACITY],
    steps: usize,
    calibration: count::Calibration,
    started: u64,
}

/// The tag of the step that concluded the estimation (Estimate →
/// Validated) in the per-step record: it is listed on its own row.
const CONCLUDING: u8 = 0;

impl Meter {
    fn instructions(&self, ticks: u64) -> u64 {
        ticks.saturating_sub(self.calibration.overhead_ticks)
            * self.calibration.instructions_per_tick
    }
}

impl Observer<ReferenceRobot<Plant>> for Meter {
    #[inline(always)]
    fn before_step(&mut self, _: &ReferenceRobot<Plant>, _: &Frame, _: StateKind) {
        self.started = count::now();
    }

    #[inline(always)]
    fn after_step(
        &mut self,
        _: &ReferenceRobot<Plant>,
        _: &Frame,
        state: StateKind,
        command: &Command,
    ) {
        let ticks = count::now() - self.started;
        let instructions = self.instructions(ticks);
        let concluding = state == StateKind::Estimate && command.state == StateKind::Validated;
        if let (Some(slot), Some(kind)) = (
            self.instructions.get_mut(self.steps),
            self.states.get_mut(self.steps),
        ) {
            *slot = u32::try_from(instructions).unwrap_or(u32::MAX);
            *kind = if concluding { CONCLUDING } else { state as u8 };
        }
        self.steps += 1;
    }

    fn event(&mut self, event: &TraceEvent) {
        hprintln!("{}", EventLine(event));
    }
}

#[entry]
fn main() -> ! {
    stack::paint();
    let peripherals = cortex_m::Peripherals::take();
    let Some(peripherals) = peripherals else {
        fail("core peripherals already taken")
    };
    count::start(peripherals.SYST);
    let calibration = count::calibrate();

    // `limb run`'s defaults: l1 = 0.30 m, l2 = 0.20 m, noise seed 1.
    let params = PlantParameters::new(0.30, 0.20);
    let Ok(plant) = Plant::new(params) else {
        fail("plant parameters")
    };
    // SAFETY: main runs once; this is the only reference to KERNEL.
    let slot = unsafe { &mut *addr_of_mut!(KERNEL) };
    let Ok(kernel) = Kernel::new_in(slot, KernelConfig::default()) else {
        fail("kernel configuration")
    };
    hprintln!(
        "limb-firmware: session on mps2-an500 (Cortex-M7), kernel {} B in a static",
        core::mem::size_of::<Kernel>()
    );
    let mut meter = Meter {
        // SAFETY: main runs once; these are the only references.
        instructions: unsafe { &mut *addr_of_mut!(INSTRUCTIONS) },
        states: unsafe { &mut *addr_of_mut!(STATES) },
        steps: 0,
        calibration,
        started: 0,
    };
    let plan = SessionPlan::default();
    let mut robot = ReferenceRobot::new(plant, plan.rate, plan.timeout);
    let Ok(outcome) = limb_session::run(kernel, &mut robot, &mut Operator::new(plan), &mut meter);
    hprintln!("{}", Digest(&outcome));

    hprintln!(
        "cost calibration instructions-per-tick {} overhead-ticks {}",
        calibration.instructions_per_tick,
        calibration.overhead_ticks
    );
    // SAFETY: main runs once; the only reference.
    let scratch = unsafe { &mut *addr_of_mut!(SCRATCH) };
    let recorded = meter.steps.min(CAPACITY);
    let rows = STATES_LISTED.map(|kind| (kind as u8, kind));
    let concluding = (CONCLUDING, StateKind::Estimate);
    for (tag, kind) in rows.into_iter().chain([concluding]) {
        let mut n = 0;
        for (&i, &s) in meter.instructions[..recorded]
            .iter()
            .zip(&meter.states[..recorded])
        {
            if s == tag {
                scratch[n] = i;
                n += 1;
            }
        }
        let counts = &mut scratch[..n];
        if counts.is_empty() {
            continue;
        }
        counts.sort_unstable();
        let median = (u64::from(counts[(n - 1) / 2]) + u64::from(counts[n / 2])) / 2;
        hprintln!(
            "cost state {:?}{} steps {} median {} max {}",
            kind,
            if tag == CONCLUDING { "-concluding" } else { "" },
            n,
            median,
            counts[n - 1]
        );
    }
    let high_water = stack::high_water();
    hprintln!(
        "stack high-water {} budget {} capacity {}",
        high_water,
        STACK_BUDGET,
        stack::capacity()
    );
    if meter.steps > CAPACITY {
        fail("more steps than the cost record holds");
    }
    if high_water > STACK_BUDGET {
        fail("the stack outgrew its budget");
    }
    let worst = meter.instructions[..recorded]
        .iter()
        .copied()
        .max()
        .unwrap_or(0);
    hprintln!(
        "worst step {} instructions, budget {}",
        worst,
        STEP_INSTRUCTION_BUDGET
    );
    if worst > STEP_INSTRUCTION_BUDGET {
        fail("a step took more instructions than its budget");
    }
    if !outcome.completed {
        fail("the session did not complete");
    }
    debug::exit(debug::EXIT_SUCCESS);
    fail("semihosting exit returned")
}

/// Prints `why` and exits QEMU with failure.
fn fail(why: &str) -> ! {
    hprintln!("limb-firmware: FAILED: {}", why);
    loop {
        debug::exit(debug::EXIT_FAILURE);
    }
}

#[exception]
fn SysTick() {
    count::on_wrap();
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    hprintln!("limb-firmware: hard fault at pc {:#010x}", frame.pc());
    fail("hard fault")
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("limb-firmware: panic: {}", info);
    fail("panic")
}
