//! Loop-latency harness: a robot-side sender paces COMMANDING_ACTIVE
//! monitoring messages at 1 kHz over loopback UDP to an `FriClient` with a
//! hold controller, and measures the round trip (send → reply received).
//! Prints p50 / p99 / max (µs) and missed cycles (reply later than 1 ms or none).
//!
//! `cargo run --release -p limb-kuka --example loop_latency -- [SECONDS] [VERSION]`

use std::net::UdpSocket;
use std::thread;
use std::time::{Duration, Instant};

use limb_kuka::messages::SessionState;
use limb_kuka::session::{CommandIntent, Controller, MonitoringView};
use limb_kuka::udp::{CycleOutcome, FriClient};
use limb_kuka::vectors::example_monitoring;
use limb_kuka::{encode_monitoring, FriVersion};

/// Send period (1 kHz).
const PERIOD: Duration = Duration::from_millis(1);

struct Hold;
impl Controller for Hold {
    fn on_monitoring(&mut self, _view: &MonitoringView, _now: f64) -> CommandIntent {
        CommandIntent::Hold
    }
    fn on_link_stale(&mut self, _silent_for: f64, _now: f64) {}
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let seconds: f64 = args.next().map_or(Ok(5.0), |text| text.parse())?;
    let version: FriVersion = args
        .next()
        .map_or(Ok(FriVersion::V1_15), |text| text.parse())?;
    let mut client = FriClient::bind(
        "127.0.0.1:0".parse()?,
        version,
        0.01,
        Duration::from_millis(200),
    )?;
    let client_address = client.local_addr()?;
    let client_thread = thread::spawn(move || {
        while let Ok(CycleOutcome::Handled { .. } | CycleOutcome::Rejected(_)) =
            client.run_cycle(&mut Hold)
        {}
    });
    let robot = UdpSocket::bind("127.0.0.1:0")?;
    robot.set_read_timeout(Some(PERIOD))?;
    let mut message = example_monitoring(SessionState::CommandingActive, version);
    let cycles = (seconds * 1000.0) as u32;
    let mut round_trips_us = Vec::with_capacity(cycles as usize);
    let mut missed = 0u32;
    let mut buffer = [0u8; 1500];
    let start = Instant::now();
    for cycle in 0..cycles {
        let due = start + PERIOD * cycle;
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            thread::sleep(wait);
        }
        message.header.sequence_counter = cycle;
        let sent = Instant::now();
        robot.send_to(&encode_monitoring(&message, version)?, client_address)?;
        match robot.recv_from(&mut buffer) {
            Ok(_) => {
                let round_trip = sent.elapsed();
                missed += u32::from(round_trip > PERIOD);
                round_trips_us.push(round_trip.as_secs_f64() * 1e6);
            }
            Err(_) => missed += 1,
        }
    }
    drop(robot);
    client_thread.join().map_err(|_| "client thread panicked")?;
    round_trips_us.sort_by(f64::total_cmp);
    let percentile = |p: f64| {
        round_trips_us
            .get(((round_trips_us.len() as f64 - 1.0) * p) as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    println!(
        "FRI {version}, {cycles} cycles at 1 kHz: round trip p50 {:.1} us, p99 {:.1} us, max {:.1} us; missed {missed}",
        percentile(0.5),
        percentile(0.99),
        percentile(1.0)
    );
    Ok(())
}
