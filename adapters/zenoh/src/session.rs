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
    config("peer", listen, connect, lease_ms)
}

/// A router (what `zenohd` runs) listening on `listen`: the deployment's
/// hub that nodes and supervisor stations connect to as clients.
///
/// # Errors
/// [`AdapterError::Zenoh`] when Zenoh refuses a value.
pub fn router_config(listen: &[String], lease_ms: u64) -> Result<zenoh::Config, AdapterError> {
    config("router", listen, &[], lease_ms)
}

/// A client of the router at `connect` (a node or a supervisor station in
/// a routed deployment): it talks only through the router.
///
/// # Errors
/// [`AdapterError::Zenoh`] when Zenoh refuses a value.
pub fn client_config(connect: &[String], lease_ms: u64) -> Result<zenoh::Config, AdapterError> {
    config("client", &[], connect, lease_ms)
}

fn config(
    mode: &str,
    listen: &[String],
    connect: &[String],
    lease_ms: u64,
) -> Result<zenoh::Config, AdapterError> {
    let mut config = zenoh::Config::default();
    let list = |endpoints: &[String]| {
        serde_json::to_string(endpoints)
            .map_err(|_| AdapterError::Setting("endpoints could not be written as JSON"))
    };
    config.insert_json5("mode", &format!("{mode:?}"))?;
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

/// Sets this session's user/password credentials
/// (`transport/auth/usrpwd`), presented to every peer that checks them.
///
/// # Errors
/// [`AdapterError::Zenoh`] when Zenoh refuses a value.
pub fn set_credentials(
    config: &mut zenoh::Config,
    user: &str,
    password: &str,
) -> Result<(), AdapterError> {
    config.insert_json5("transport/auth/usrpwd/user", &json_string(user)?)?;
    config.insert_json5("transport/auth/usrpwd/password", &json_string(password)?)?;
    Ok(())
}

/// Zenoh-level protection of a node's commands:
/// - peers must authenticate with a user and password listed in
///   `dictionary_file` (lines `user:password`); others cannot connect;
/// - Zenoh's access control drops, at ingress, every `put` on `cmd/request`
///   from the users in `observers` (monitoring stations, safety panels): they
///   can read telemetry, query and send the emergency stop, never a
///   command. Everything else is allowed.
///
/// # Errors
/// [`AdapterError::Zenoh`] when Zenoh refuses a value.
pub fn protect_commands(
    config: &mut zenoh::Config,
    keys: &crate::keys::Keys,
    dictionary_file: &std::path::Path,
    observers: &[String],
) -> Result<(), AdapterError> {
    let dictionary = dictionary_file
        .to_str()
        .ok_or(AdapterError::Setting("the dictionary path must be UTF-8"))?;
    config.insert_json5(
        "transport/auth/usrpwd/dictionary_file",
        &json_string(dictionary)?,
    )?;
    let access_control = serde_json::json!({
        "enabled": true,
        "default_permission": "allow",
        "rules": [{
            "id": "no-commands",
            "messages": ["put"],
            "flows": ["ingress"],
            "permission": "deny",
            "key_exprs": [keys.request()],
        }],
        "subjects": [{ "id": "observers", "usernames": observers }],
        "policies": [{ "rules": ["no-commands"], "subjects": ["observers"] }],
    });
    config.insert_json5("access_control", &access_control.to_string())?;
    Ok(())
}

fn json_string(value: &str) -> Result<String, AdapterError> {
    serde_json::to_string(value).map_err(|_| AdapterError::Setting("cannot quote a string"))
}

/// PEM files of Zenoh's TLS transport.
#[cfg(feature = "tls")]
#[derive(Clone, Debug)]
pub struct TlsFiles {
    /// Certificate of the authority that signed the listener's certificate
    /// (what a connecting side trusts).
    pub root_ca: std::path::PathBuf,
    /// The listener's certificate chain and private key; `None` on a side
    /// that only connects.
    pub listener: Option<(std::path::PathBuf, std::path::PathBuf)>,
}

/// Configures Zenoh's TLS transport (`transport/link/tls`): listeners
/// present `files.listener`, connections verify the peer's certificate
/// against `files.root_ca` and its name against the endpoint's host
/// (`tls/<host>:<port>` endpoints). Encrypts telemetry and commands on the
/// wire; the HMAC signatures of commands stay as they are.
///
/// # Errors
/// [`AdapterError::Setting`] for a path that is not UTF-8,
/// [`AdapterError::Zenoh`] when Zenoh refuses a value.
#[cfg(feature = "tls")]
pub fn set_tls(config: &mut zenoh::Config, files: &TlsFiles) -> Result<(), AdapterError> {
    let path = |p: &std::path::Path| {
        p.to_str()
            .ok_or(AdapterError::Setting("TLS file paths must be UTF-8"))
            .and_then(json_string)
    };
    config.insert_json5(
        "transport/link/tls/root_ca_certificate",
        &path(&files.root_ca)?,
    )?;
    if let Some((certificate, key)) = &files.listener {
        config.insert_json5("transport/link/tls/listen_certificate", &path(certificate)?)?;
        config.insert_json5("transport/link/tls/listen_private_key", &path(key)?)?;
    }
    Ok(())
}
