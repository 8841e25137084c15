//! Telemetry at 1 kHz over loopback: a node stepping the kernel every 1 ms
//! publishes every sample; a subscriber in another session counts them and
//! measures the latency from the step to the subscriber's callback.
//!
//! ```sh
//! cargo run --release -p limb-zenoh --example telemetry_bench -- [seconds] [json|cbor]
//! ```
//! Prints the delivered rate and the p50 / p99 / max latency.

use limb_zenoh::auth::CommandKey;
use limb_zenoh::link::{wall_clock_ns, LinkSettings, LivenessPolicy, OnSupervisorLoss};
use limb_zenoh::node::{LoopSettings, Node};
use limb_zenoh::sensor::ScriptedLift;
use limb_zenoh::session::{free_loopback_port, peer_config};
use limb_zenoh::wire::{SampleMessage, WireFormat};
use limb_zenoh::AdapterError;
use std::sync::mpsc::channel;
use std::time::Duration;
use zenoh::Wait;

fn main() -> Result<(), AdapterError> {
    let mut args = std::env::args().skip(1);
    let seconds: u64 = args
        .next()
        .and_then(|a| a.parse().ok())
        .unwrap_or(5)
        .clamp(1, 60);
    let format = match args.next().as_deref() {
        Some("json") => WireFormat::Json,
        _ => WireFormat::Cbor,
    };
    let period = Duration::from_millis(1);
    let lift = ScriptedLift::reference();
    let (kernel, origin) = lift.kernel_after_lift();
    let endpoint = format!("tcp/127.0.0.1:{}", free_loopback_port()?);
    let settings = LinkSettings {
        robot_id: "bench".into(),
        format,
        command_key: CommandKey::new(b"benchmark key, not a secret")?,
        sample_decimation: 1,
        status_period: 0.1,
        liveness: LivenessPolicy {
            timeout: Duration::from_secs(1),
            on_loss: OnSupervisorLoss::Continue,
        },
    };
    let node = Node::spawn(
        peer_config(std::slice::from_ref(&endpoint), &[], 1000)?,
        &settings,
        LoopSettings { period, origin },
        kernel,
        Box::new(lift),
    )?;
    let session = zenoh::open(peer_config(&[], &[endpoint], 1000)?).wait()?;
    let (tx, samples) = channel();
    let keys = limb_zenoh::keys::Keys::new("bench")?;
    let _subscriber = session
        .declare_subscriber(keys.sample())
        .callback(move |sample| {
            let received = wall_clock_ns();
            if let Ok(m) = format.decode::<SampleMessage>(&sample.payload().to_bytes()) {
                let _ = tx.send((m.step, received.saturating_sub(m.sent_at_ns)));
            }
        })
        .wait()?;
    // Let the connection settle, then measure a window of whole seconds.
    std::thread::sleep(Duration::from_millis(500));
    samples.try_iter().for_each(drop);
    std::thread::sleep(Duration::from_secs(seconds));
    let window: Vec<(u64, u64)> = samples.try_iter().collect();
    node.shutdown()?;
    session.close().wait()?;

    let (Some(first), Some(last)) = (window.first(), window.last()) else {
        println!("no samples received");
        return Ok(());
    };
    let published = last.0 - first.0 + 1;
    let mut latencies: Vec<u64> = window.iter().map(|(_, l)| *l).collect();
    latencies.sort_unstable();
    let at = |q: f64| {
        let index = ((latencies.len() - 1) as f64 * q).round() as usize;
        latencies[index] as f64 / 1000.0
    };
    println!(
        "{format:?}, {seconds} s at 1 kHz: received {} of {published} steps ({:.1} %), \
         rate {:.0} Hz; latency step → subscriber p50 {:.0} µs, p99 {:.0} µs, max {:.0} µs",
        window.len(),
        100.0 * window.len() as f64 / published as f64,
        window.len() as f64 / seconds as f64,
        at(0.5),
        at(0.99),
        at(1.0),
    );
    Ok(())
}
