//! Loop-latency harness: the simulated FRI controller paced at a 1 ms send
//! period (real time) and the FRI client with the kernel inside, over
//! loopback UDP, for SECONDS (≥ 60 s for the README figures). The kernel
//! runs the whole session (estimation motion, manipulation, hold). Round
//! trip = monitoring datagram sent → its reply received by the controller
//! (includes the kernel's step, kinematics and both codecs); a missed cycle
//! = no reply before the next send tick.
//!
//! `cargo run --release -p limb-kuka --example loop_latency -- [SECONDS] [VERSION] [joint|wrench]`

use limb_kuka::loopback::run_reference_session;
use limb_kuka::robot::Overlay;
use limb_kuka::sim_controller::{Pacing, SimSettings};
use limb_kuka::FriVersion;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let seconds: f64 = args.next().map_or(Ok(60.0), |text| text.parse())?;
    let version: FriVersion = args
        .next()
        .map_or(Ok(FriVersion::V1_15), |text| text.parse())?;
    let overlay = match args.next().as_deref() {
        None | Some("joint") => Overlay::JointPosition,
        Some("wrench") => Overlay::Wrench,
        Some(other) => return Err(format!("overlay `{other}`: joint or wrench").into()),
    };
    let mut sim = SimSettings::new(version);
    sim.pacing = Pacing::RealTime;
    sim.overlay = overlay;
    let cycles = (seconds * 1000.0).round() as u64;
    let started = std::time::Instant::now();
    let run = run_reference_session(sim, cycles, |_, _| false)?;
    let wall = started.elapsed().as_secs_f64();
    let stats = run.sim.stats();
    let latency = stats.latency();
    println!(
        "FRI {version} {overlay:?}, {} cycles at 1 kHz in {wall:.1} s wall: round trip p50 {:.0} us, \
         p99 {:.0} us, max {:.0} us; missed {} (of which {} answered late); \
         commanding cycles {}; kernel {:?}, steps {}, events {:?}",
        stats.cycles,
        latency.p50_us,
        latency.p99_us,
        latency.max_us,
        stats.missed_cycles,
        stats.late_replies,
        stats.state_cycles[4],
        run.kernel.state().kind(),
        run.outcome.steps,
        run.events
            .iter()
            .map(limb_session::operator::describe)
            .collect::<Vec<_>>(),
    );
    if let Some(model) = run.outcome.model {
        println!("model: {model:?}");
    }
    Ok(())
}
