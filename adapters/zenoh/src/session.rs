//! Zenoh session configurations.
//!
//! Tests and single-host setups use [`peer_config`]: peer mode, multicast
//! scouting off, explicit TCP endpoints. In a deployment, put a router
//! (`zenohd`) on the robot's controller and give both sides
//! `connect/endpoints = ["tcp/<controller>:7447"]` with `mode = "client"` or
//! `"peer"` (see the README); the key expressions and the code do not
//! change.

use crate::error::AdapterError;

/// A peer-mode configuration that listens on `listen` and connects to
/// `connect` (endpoints such as `tcp/127.0.0.1:7447`), with multicast
/// scouting off so that unrelated sessions never find each other, and a
/// lease of `lease_ms` [ms] (Zenoh's default is 10 000) so that a dead peer
/// is seen quickly.
///
/// # Errors
/// [`AdapterError::Zenoh`] when Zenoh refuses a value.
pub fn peer_config(
    listen: &[String],
    connect: &[String],
    lease_ms: u64,
) -> Result<zenoh::Config, AdapterError> {
    let mut config = zenoh::Config::default();
    let list = |endpoints: &[String]| {
        serde_json::to_string(endpoints)
            .map_err(|_| AdapterError::Setting("endpoints could not be written as JSON"))
    };
    config.insert_json5("mode", r#""peer""#)?;
    config.insert_json5("scouting/multicast/enabled", "false")?;
    config.insert_json5("scouting/gossip/enabled", "false")?;
    config.insert_json5("listen/endpoints", &list(listen)?)?;
    config.insert_json5("connect/endpoints", &list(connect)?)?;
    config.insert_json5("transport/link/tx/lease", &lease_ms.to_string())?;
    Ok(config)
}

/// A free TCP port on 127.0.0.1 (bound once and released; another process
/// could take it in between, which tests accept).
///
/// # Errors
/// [`AdapterError::Thread`] when no port can be bound.
pub fn free_loopback_port() -> Result<u16, AdapterError> {
    let listener = std::net::TcpListener::bind("127.0.0.1:0")?;
    Ok(listener.local_addr()?.port())
}
