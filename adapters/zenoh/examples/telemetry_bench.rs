//! Telemetry at 1 kHz over loopback, side by side: for each sample QoS
//! (batched through the publisher thread, the default; express;
//! express from the loop; express from the loop at priority RealTime) a
//! node steps the kernel every 1 ms and publishes every sample, and a
//! subscriber in another session measures the latency from the control
//! step (`sent_at_ns`, stamped in the loop) to its callback. The
//! configurations take turns in rounds, so they share the machine's load.
//!
//! Zenoh reads its runtime thread counts once per process (environment
//! variable `ZENOH_RUNTIME`), so the runtime settings cannot alternate
//! inside one process: with `runtimes` the bench re-runs itself, one child
//! process per round and runtime setting (Zenoh's own thread counts, then
//! [`ONE_WORKER_RUNTIME`]), taking turns like the QoS settings, and
//! reports every (runtime, QoS) pair.
//!
//! ```sh
//! cargo run --release -p limb-zenoh --example telemetry_bench -- [seconds per run] [rounds] [json|cbor] [runtimes]
//! ```
//! Prints one line per configuration: delivered share, rate, p50 / p99 /
//! max latency over all its rounds.

#[path = "../tests/common/lift.rs"]
mod lift;

use lift::Lift;
use limb_zenoh::auth::CommandKey;
use limb_zenoh::link::{LinkSettings, SampleQos};
use limb_zenoh::node::Node;
use limb_zenoh::session::{free_loopback_port, peer_config};
use limb_zenoh::supervision::{wall_clock_ns, LivenessPolicy, OnSupervisorLoss};
use limb_zenoh::wire::{SampleMessage, WireFormat};
use limb_zenoh::AdapterError;
use std::process::Command;
use std::sync::mpsc::channel;
use std::time::Duration;
use zenoh::qos::Priority;
use zenoh::Wait;

/// One worker thread for each of Zenoh's runtimes (the value of
/// `ZENOH_RUNTIME`): on a 2-core machine Zenoh's default thread counts put
/// more threads than cores at the node's real-time priority.
const ONE_WORKER_RUNTIME: &str = "(app: (worker_threads: 1), acc: (worker_threads: 1), \
     tx: (worker_threads: 1), rx: (worker_threads: 1), net: (worker_threads: 1))";

/// Marks a child's result line.
const CHILD_LINE: &str = "tally";

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
    let lift = Lift::reference().stepping(Duration::from_millis(1));
    let (kernel, lift) = lift.kernel_after_lift();
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
        Some(Duration::from_millis(1)),
        kernel,
        lift,
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

/// The sample QoS settings compared, named.
fn configurations() -> [(&'static str, SampleQos); 4] {
    [
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
    ]
}

impl Tally {
    /// One line a child prints for its parent: published, received,
    /// seconds, then every latency [ns].
    fn to_line(&self, index: usize) -> String {
        let latencies: Vec<String> = self.latencies_ns.iter().map(u64::to_string).collect();
        format!(
            "{CHILD_LINE} {index} {} {} {} {}",
            self.published,
            self.received,
            self.seconds,
            latencies.join(",")
        )
    }

    /// Adds a child's line for configuration `index`; `false` when the
    /// line is not one.
    fn add_line(&mut self, index: usize, line: &str) -> bool {
        let fields: Vec<&str> = line.split(' ').collect();
        let [CHILD_LINE, i, published, received, seconds, latencies] = fields[..] else {
            return false;
        };
        let (Ok(i), Ok(published), Ok(received), Ok(seconds)) = (
            i.parse::<usize>(),
            published.parse::<u64>(),
            received.parse::<usize>(),
            seconds.parse::<u64>(),
        ) else {
            return false;
        };
        if i != index {
            return false;
        }
        self.published += published;
        self.received += received;
        self.seconds += seconds;
        self.latencies_ns
            .extend(latencies.split(',').filter_map(|l| l.parse::<u64>().ok()));
        true
    }

    /// Prints the figures of configuration `name`.
    fn report(&mut self, name: &str) {
        let latencies = &mut self.latencies_ns;
        if latencies.is_empty() {
            println!("{name}: no samples received");
            return;
        }
        latencies.sort_unstable();
        let at = |q: f64| {
            let index = ((latencies.len() - 1) as f64 * q).round() as usize;
            latencies[index] as f64 / 1000.0
        };
        println!(
            "{name}: received {} of {} steps ({:.1} %), {:.0} Hz; latency step → subscriber \
             p50 {:.0} µs, p99 {:.0} µs, max {:.0} µs",
            self.received,
            self.published,
            100.0 * self.received as f64 / self.published.max(1) as f64,
            self.received as f64 / self.seconds as f64,
            at(0.5),
            at(0.99),
            at(1.0),
        );
    }
}

/// Runs one round of every QoS setting in a child process with Zenoh's
/// runtime setting `runtime` (`None`: Zenoh's own), adding to `tallies`.
fn child_round(
    seconds: u64,
    format: &str,
    runtime: Option<&str>,
    tallies: &mut [Tally],
) -> Result<(), Box<dyn std::error::Error>> {
    let mut command = Command::new(std::env::current_exe()?);
    command.args([seconds.to_string().as_str(), "1", format, "child"]);
    match runtime {
        Some(value) => command.env("ZENOH_RUNTIME", value),
        None => command.env_remove("ZENOH_RUNTIME"),
    };
    let output = command.output()?;
    let text = String::from_utf8_lossy(&output.stdout);
    for (index, tally) in tallies.iter_mut().enumerate() {
        if !text.lines().any(|line| tally.add_line(index, line)) {
            return Err(format!(
                "child round gave no result for configuration {index}: {}",
                String::from_utf8_lossy(&output.stderr)
            )
            .into());
        }
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number = |at: usize, default: u64| {
        args.get(at)
            .and_then(|a| a.parse().ok())
            .unwrap_or(default)
            .clamp(1, 60)
    };
    let seconds = number(0, 3);
    let rounds = number(1, 3);
    let (format, format_name) = match args.get(2).map(String::as_str) {
        Some("json") => (WireFormat::Json, "json"),
        _ => (WireFormat::Cbor, "cbor"),
    };
    let configurations = configurations();
    match args.get(3).map(String::as_str) {
        Some("child") => {
            for (index, (_, qos)) in configurations.iter().enumerate() {
                let mut tally = Tally::default();
                run(*qos, format, seconds, &mut tally)?;
                println!("{}", tally.to_line(index));
            }
        }
        Some("runtimes") => {
            let runtimes = [
                ("Zenoh's runtime threads", None),
                ("one worker per runtime", Some(ONE_WORKER_RUNTIME)),
            ];
            let mut tallies: Vec<Vec<Tally>> = runtimes
                .iter()
                .map(|_| configurations.iter().map(|_| Tally::default()).collect())
                .collect();
            for _ in 0..rounds {
                for ((_, runtime), tallies) in runtimes.iter().zip(tallies.iter_mut()) {
                    child_round(seconds, format_name, *runtime, tallies)?;
                }
            }
            println!(
                "{format:?}, 1 kHz, {rounds} rounds of {seconds} s per configuration, \
                 runtimes alternating by process:"
            );
            for ((runtime, _), tallies) in runtimes.iter().zip(tallies.iter_mut()) {
                for ((name, _), tally) in configurations.iter().zip(tallies.iter_mut()) {
                    tally.report(&format!("{runtime}; {name}"));
                }
            }
        }
        _ => {
            let mut tallies: Vec<Tally> = configurations.iter().map(|_| Tally::default()).collect();
            for _ in 0..rounds {
                for ((_, qos), tally) in configurations.iter().zip(tallies.iter_mut()) {
                    run(*qos, format, seconds, tally)?;
                }
            }
            println!("{format:?}, 1 kHz, {rounds} rounds of {seconds} s per configuration:");
            for ((name, _), tally) in configurations.iter().zip(tallies.iter_mut()) {
                tally.report(name);
            }
        }
    }
    Ok(())
}
