//! Telemetry at 1 kHz over loopback, side by side: for each sample QoS
//! (batched through the publisher thread, the default; express;
//! express from the loop; express from the loop at priority RealTime) a
//! node steps the kernel every 1 ms and publishes every sample, and a
//! subscriber in another session measures the latency from the control
//! step (`sent_at_ns`, stamped in the loop) to its callback. The
//! configurations take turns in rounds, so they share the machine's load.
//!
//! ```sh
//! cargo run --release -p limb-zenoh --example telemetry_bench -- [seconds per run] [rounds] [json|cbor]
//! ```
//! Prints one line per configuration: delivered share, rate, p50 / p99 /
//! max latency over all its rounds.

use limb_zenoh::auth::CommandKey;
use limb_zenoh::link::{wall_clock_ns, LinkSettings, LivenessPolicy, OnSupervisorLoss, SampleQos};
use limb_zenoh::node::{LoopSettings, Node};
use limb_zenoh::sensor::ScriptedLift;
use limb_zenoh::session::{free_loopback_port, peer_config};
use limb_zenoh::wire::{SampleMessage, WireFormat};
use limb_zenoh::AdapterError;
use std::sync::mpsc::channel;
use std::time::Duration;
use zenoh::qos::Priority;
use zenoh::Wait;

/// What one run delivered.
#[derive(Default)]
struct Tally {
    received: usize,
    published: u64,
    seconds: u64,
    latencies_ns: Vec<u64>,
}

/// One node and one subscriber for `seconds` with `qos`.
fn run(
    qos: SampleQos,
    format: WireFormat,
    seconds: u64,
    tally: &mut Tally,
) -> Result<(), AdapterError> {
    let lift = ScriptedLift::reference();
    let (kernel, origin) = lift.kernel_after_lift();
    let endpoint = format!("tcp/127.0.0.1:{}", free_loopback_port()?);
    let settings = LinkSettings {
        robot_id: "bench".into(),
        format,
        command_key: CommandKey::new(b"benchmark key, not a secret")?,
        sample_decimation: 1,
        sample_qos: qos,
        status_period: 0.1,
        liveness: LivenessPolicy {
            timeout: Duration::from_secs(1),
            on_loss: OnSupervisorLoss::Continue,
        },
    };
    let node = Node::spawn(
        peer_config(std::slice::from_ref(&endpoint), &[], 1000)?,
        &settings,
        LoopSettings {
            period: Duration::from_millis(1),
            origin,
        },
        kernel,
        Box::new(lift),
    )?;
    let session = zenoh::open(peer_config(&[], &[endpoint], 1000)?).wait()?;
    let (tx, samples) = channel();
    let keys = limb_zenoh::keys::Keys::new("bench")?;
    let subscriber = session
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
    drop(subscriber);
    node.shutdown()?;
    session.close().wait()?;
    if let (Some(first), Some(last)) = (window.first(), window.last()) {
        tally.published += last.0 - first.0 + 1;
        tally.received += window.len();
    }
    tally.seconds += seconds;
    tally.latencies_ns.extend(window.iter().map(|(_, l)| *l));
    Ok(())
}

fn main() -> Result<(), AdapterError> {
    let mut args = std::env::args().skip(1);
    let mut number = |default: u64| {
        args.next()
            .and_then(|a| a.parse().ok())
            .unwrap_or(default)
            .clamp(1, 60)
    };
    let seconds = number(3);
    let rounds = number(3);
    let format = match std::env::args().nth(3).as_deref() {
        Some("json") => WireFormat::Json,
        _ => WireFormat::Cbor,
    };
    let configurations = [
        (
            "batched, DataHigh, publisher thread (default)",
            SampleQos::BATCHED,
        ),
        (
            "express, DataHigh, publisher thread",
            SampleQos {
                express: true,
                ..SampleQos::BATCHED
            },
        ),
        ("express, DataHigh, from the loop", SampleQos::LOW_LATENCY),
        (
            "express, RealTime, from the loop",
            SampleQos {
                priority: Priority::RealTime,
                ..SampleQos::LOW_LATENCY
            },
        ),
    ];
    let mut tallies: Vec<Tally> = configurations.iter().map(|_| Tally::default()).collect();
    for _ in 0..rounds {
        for ((_, qos), tally) in configurations.iter().zip(tallies.iter_mut()) {
            run(*qos, format, seconds, tally)?;
        }
    }
    println!("{format:?}, 1 kHz, {rounds} rounds of {seconds} s per configuration:");
    for ((name, _), tally) in configurations.iter().zip(tallies.iter_mut()) {
        let latencies = &mut tally.latencies_ns;
        if latencies.is_empty() {
            println!("{name}: no samples received");
            continue;
        }
        latencies.sort_unstable();
        let at = |q: f64| {
            let index = ((latencies.len() - 1) as f64 * q).round() as usize;
            latencies[index] as f64 / 1000.0
        };
        println!(
            "{name}: received {} of {} steps ({:.1} %), {:.0} Hz; latency step → subscriber \
             p50 {:.0} µs, p99 {:.0} µs, max {:.0} µs",
            tally.received,
            tally.published,
            100.0 * tally.received as f64 / tally.published.max(1) as f64,
            tally.received as f64 / tally.seconds as f64,
            at(0.5),
            at(0.99),
            at(1.0),
        );
    }
    Ok(())
}
