//! `limb zenoh` processes on loopback.

mod common;

use std::process::{Command, Stdio};

/// Finding 6 of issue 18: the CLI installs a `tracing` subscriber, so a
/// node's refusal of an unsigned command is logged on its stderr (with the
/// default filter, and with a `RUST_LOG` filter).
#[test]
fn a_node_logs_the_commands_it_refuses() {
    let dir = std::env::temp_dir().join(format!("limb-zenoh-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let key = dir.join("key");
    let wrong = dir.join("wrong-key");
    std::fs::write(&key, "the robot's shared secret\n").unwrap();
    std::fs::write(&wrong, "somebody else's secret\n").unwrap();
    for rust_log in [None, Some("limb_zenoh=warn,zenoh=off")] {
        let port = std::net::TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let endpoint = format!("tcp/127.0.0.1:{port}");
        let mut node = Command::new(env!("CARGO_BIN_EXE_limb"));
        node.args([
            "zenoh", "node", "--robot", "cli-test", "--listen", &endpoint,
        ])
        .arg("--key-file")
        .arg(&key)
        .args(["--seconds", "4", "--log"])
        .arg(dir.join("node.csv"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
        match rust_log {
            Some(filter) => node.env("RUST_LOG", filter),
            None => node.env_remove("RUST_LOG"),
        };
        let node = node.spawn().unwrap();
        let send = Command::new(env!("CARGO_BIN_EXE_limb"))
            .args([
                "zenoh",
                "send",
                "--robot",
                "cli-test",
                "--connect",
                &endpoint,
            ])
            .arg("--key-file")
            .arg(&wrong)
            .arg("stop")
            .output()
            .unwrap();
        let ack = common::json_of(&send);
        assert_eq!(ack["outcome"]["reason"], "unauthorised", "{ack}");
        let node = node.wait_with_output().unwrap();
        let log = String::from_utf8_lossy(&node.stderr);
        assert!(node.status.success(), "{log}");
        assert!(
            log.contains("command refused") && log.contains("Unauthorised"),
            "RUST_LOG={rust_log:?}: {log}"
        );
        // The node's session log: the plant.md header, a row per step.
        let rows = std::fs::read_to_string(dir.join("node.csv")).unwrap();
        let mut lines = rows.lines();
        assert!(lines
            .next()
            .unwrap()
            .starts_with("t,xd,zd,psid,x,y,z,psi,fx,fz,ty,q1"));
        assert!(lines.count() > 100, "{rows}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--zenoh-config FILE`: Zenoh's own JSON5 configuration, here
/// user/password authentication and an access-control rule that drops
/// every command `put` of the user `panel` at the node's ingress. The
/// supervisor's signed stop is acknowledged; the panel's, signed with the
/// same key, never reaches the node (no ack, `limb zenoh send` fails), but
/// its emergency stop does.
#[test]
fn a_zenoh_configuration_file_sets_access_control() {
    let dir = std::env::temp_dir().join(format!("limb-zenoh-acl-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let key = dir.join("key");
    std::fs::write(&key, "the robot's shared secret\n").unwrap();
    let dictionary = dir.join("users.txt");
    std::fs::write(&dictionary, "supervisor:supervisor-pw\npanel:panel-pw\n").unwrap();
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let scouting = r#"scouting: { multicast: { enabled: false }, gossip: { enabled: false } }"#;
    let node_config = dir.join("node.json5");
    std::fs::write(
        &node_config,
        format!(
            r#"{{ mode: "peer", {scouting},
  transport: {{ auth: {{ usrpwd: {{ user: "node", password: "node-pw", dictionary_file: "{}" }} }} }},
  access_control: {{ enabled: true, default_permission: "allow",
    rules: [{{ id: "no-commands", messages: ["put"], flows: ["ingress"], permission: "deny",
               key_exprs: ["limb/cli-acl/@v2/cmd/request"] }}],
    subjects: [{{ id: "observers", usernames: ["panel"] }}],
    policies: [{{ rules: ["no-commands"], subjects: ["observers"] }}] }} }}"#,
            dictionary.display()
        ),
    )
    .unwrap();
    let user_config = |user: &str| {
        let file = dir.join(format!("{user}.json5"));
        std::fs::write(
            &file,
            format!(
                r#"{{ mode: "peer", {scouting},
  transport: {{ auth: {{ usrpwd: {{ user: "{user}", password: "{user}-pw" }} }} }} }}"#
            ),
        )
        .unwrap();
        file
    };
    let node = Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(["zenoh", "node", "--robot", "cli-acl", "--listen", &endpoint])
        .arg("--zenoh-config")
        .arg(&node_config)
        .arg("--key-file")
        .arg(&key)
        .args(["--seconds", "12"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let send = |user: &str, what: &[&str]| {
        let mut command = Command::new(env!("CARGO_BIN_EXE_limb"));
        command
            .args([
                "zenoh",
                what[0],
                "--robot",
                "cli-acl",
                "--connect",
                &endpoint,
            ])
            .arg("--zenoh-config")
            .arg(user_config(user));
        if what[0] == "send" {
            command.arg("--key-file").arg(&key);
        }
        command.args(&what[1..]).output().unwrap()
    };
    let panel = send("panel", &["send", "stop"]);
    assert!(
        !panel.status.success(),
        "the panel's command was acknowledged"
    );
    let supervisor = send("supervisor", &["send", "stop"]);
    let ack = common::json_of(&supervisor);
    assert_eq!(ack["outcome"]["outcome"], "accepted", "{ack}");
    let estop = send("panel", &["estop"]);
    assert!(
        estop.status.success(),
        "{}",
        String::from_utf8_lossy(&estop.stderr)
    );
    let node = node.wait_with_output().unwrap();
    assert!(
        node.status.success(),
        "{}",
        String::from_utf8_lossy(&node.stderr)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
