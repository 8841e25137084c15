//! Golden frames: every example in `PROTOCOL.md` marked
//! `<!-- golden: NAME -->` is exactly the hex of the frame this crate
//! encodes for NAME, and decodes back to it.

use limb_arebo::protocol::{
    status_byte, Command, ControlType, Decoder, Telemetry, COMMAND_HEADER, TELEMETRY_HEADER,
};
use std::collections::BTreeMap;

fn hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// NAME → the text of the fenced block after `<!-- golden: NAME -->`.
fn documented() -> BTreeMap<String, String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/PROTOCOL.md");
    let text = std::fs::read_to_string(path).unwrap();
    let mut blocks = BTreeMap::new();
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        let Some(name) = line
            .trim()
            .strip_prefix("<!-- golden: ")
            .and_then(|l| l.strip_suffix(" -->"))
        else {
            continue;
        };
        assert!(lines.next().is_some_and(|l| l.starts_with("```")), "{name}");
        let body: Vec<&str> = lines
            .by_ref()
            .take_while(|l| !l.starts_with("```"))
            .collect();
        assert!(
            blocks.insert(name.to_owned(), body.join(" ")).is_none(),
            "{name}"
        );
    }
    blocks
}

fn frame() -> Telemetry {
    Telemetry {
        status: status_byte(true, ControlType::Torque),
        error: 0,
        packet: 7,
        run_time_ms: 1234,
        counts: [1000, -2000, 3000, 40, -50],
        torques: [0.5, 9.75, -3.0],
        commanded: [0.0, 10.5, -2.5],
    }
}

#[test]
fn the_documented_frames_are_the_encoded_ones() {
    let commands = [
        ("heartbeat", Command::Heartbeat),
        (
            "set_control_torque",
            Command::SetControlType(ControlType::Torque),
        ),
        (
            "set_control_target",
            Command::SetControlTarget([0.5, -1.25, 2.0]),
        ),
    ];
    let documented = documented();
    for (name, command) in commands {
        let bytes = command.encode();
        assert_eq!(documented[name].trim(), hex(&bytes), "{name}");
        let mut decoder = Decoder::new(COMMAND_HEADER);
        let payload = bytes.iter().find_map(|b| decoder.push(*b)).unwrap();
        assert_eq!(Command::parse(&payload), Some(command), "{name}");
    }
    let bytes = frame().encode();
    assert_eq!(documented["stream_frame"].trim(), hex(&bytes));
    let mut decoder = Decoder::new(TELEMETRY_HEADER);
    let payload = bytes.iter().find_map(|b| decoder.push(*b)).unwrap();
    assert_eq!(Telemetry::parse(&payload), Some(frame()));
    assert_eq!(
        documented.len(),
        commands.len() + 1,
        "every block is checked"
    );
}
