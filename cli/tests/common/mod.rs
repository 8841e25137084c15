//! Helpers shared by the CLI tests.

use std::process::Output;

/// The one JSON object a successful `--json` run printed; fails the test
/// with the run's stderr when it exited non-zero.
pub fn json_of(out: &Output) -> serde_json::Value {
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}
