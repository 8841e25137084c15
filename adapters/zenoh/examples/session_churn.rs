//! Memory of opening and closing Zenoh sessions, without the kernel or
//! the node: `cargo run --release -p limb-zenoh --example session_churn --
//! [PAIRS] [SAMPLES]` opens PAIRS (default 100) pairs of peer sessions on a
//! fresh loopback port each, as `limb soak zenoh` does for its node and
//! supervisor, sends SAMPLES (default 20 000) samples from one to a
//! subscriber on the other, closes both, and prints the peak (VmHWM) and
//! current (VmRSS) resident memory [kB] every 10 pairs. It tells whether
//! the soak's growth of the peak over its sessions is Zenoh's own.

use limb_zenoh::session::{free_loopback_port, peer_config};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;
use zenoh::Wait;

/// The VmHWM and VmRSS lines of this process's status, joined.
fn memory() -> String {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let lines: Vec<&str> = status
        .lines()
        .filter(|line| line.starts_with("VmHWM") || line.starts_with("VmRSS"))
        .collect();
    lines
        .join(" ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

fn main() -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let mut args = std::env::args().skip(1);
    let pairs: usize = args.next().map_or(Ok(100), |a| a.parse())?;
    let samples: usize = args.next().map_or(Ok(20_000), |a| a.parse())?;
    let received = Arc::new(AtomicU64::new(0));
    println!("pair, memory, samples received");
    for pair in 1..=pairs {
        let endpoint = format!("tcp/127.0.0.1:{}", free_loopback_port()?);
        let node = zenoh::open(peer_config(std::slice::from_ref(&endpoint), &[], 1000)?).wait()?;
        let station =
            zenoh::open(peer_config(&[], std::slice::from_ref(&endpoint), 1000)?).wait()?;
        let count = Arc::clone(&received);
        let subscriber = station
            .declare_subscriber("churn/sample")
            .callback(move |_| {
                count.fetch_add(1, Ordering::Relaxed);
            })
            .wait()?;
        std::thread::sleep(Duration::from_millis(200));
        let publisher = node.declare_publisher("churn/sample").wait()?;
        for i in 0..samples {
            publisher.put(i.to_le_bytes().to_vec()).wait()?;
        }
        std::thread::sleep(Duration::from_millis(100));
        drop(publisher);
        drop(subscriber);
        node.close().wait()?;
        station.close().wait()?;
        if pair % 10 == 0 {
            println!("{pair}, {}, {}", memory(), received.load(Ordering::Relaxed));
        }
    }
    Ok(())
}
