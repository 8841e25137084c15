//! Helpers shared by the CLI tests.

use std::process::Output;

/// The one JSON object a successful `--json` run printed; fails the test
/// with the run's stderr when it exited non-zero.
#[allow(dead_code)]
pub fn json_of(out: &Output) -> serde_json::Value {
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

/// The Rust `Debug` shapes a user-facing text must not hold (the kernel's
/// vocabulary spells everything: `limb_kernel::vocabulary`): an enum
/// variant with a payload (`Monitor(`, `Some(`), a struct (`JointAngles {
/// shoulder_elevation: …`). Returns the first found, with its context.
#[allow(dead_code)]
pub fn debug_shape(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    for (i, window) in bytes.windows(2).enumerate() {
        // `Ident(` with a capitalised identifier right before the parenthesis.
        if window[1] == b'(' && window[0].is_ascii_alphanumeric() {
            let start = text[..=i]
                .rfind(|c: char| !c.is_ascii_alphanumeric() && c != '_')
                .map_or(0, |p| p + 1);
            let word = &text[start..=i];
            if word.starts_with(|c: char| c.is_ascii_uppercase()) {
                return Some(context(text, start));
            }
        }
        // `Ident { field: ` (a struct's Debug).
        if window == b" {" && i > 0 && bytes[i - 1].is_ascii_alphanumeric() {
            let rest = &text[i + 2..];
            let field: String = rest
                .trim_start()
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if !field.is_empty() && rest.trim_start()[field.len()..].starts_with(':') {
                return Some(context(text, i));
            }
        }
    }
    None
}

fn context(text: &str, at: usize) -> String {
    let start = text[..at]
        .char_indices()
        .rev()
        .nth(30)
        .map_or(0, |(p, _)| p);
    let end = text[at..]
        .char_indices()
        .nth(50)
        .map_or(text.len(), |(p, _)| at + p);
    text[start..end].to_string()
}

/// Fails the test when `text` (what `what` printed) holds a `Debug` shape.
#[allow(dead_code)]
pub fn assert_no_debug_shape(what: &str, text: &str) {
    if let Some(found) = debug_shape(text) {
        panic!("{what} prints a Rust Debug shape: …{found}…");
    }
}

/// True when `path` (a tool a test needs, set up by `setup`) exists; in CI
/// (`CI` set) a missing tool fails the test, elsewhere the test says it
/// skipped.
#[allow(dead_code)]
pub fn tool_ready(path: &std::path::Path, setup: &str) -> bool {
    if path.exists() {
        return true;
    }
    assert!(
        std::env::var_os("CI").is_none(),
        "CI must have {}: run {setup}",
        path.display()
    );
    eprintln!("skipped: {} is missing (run {setup})", path.display());
    false
}
