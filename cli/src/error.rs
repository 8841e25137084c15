//! Errors of the `limb` command and their exit codes (`../shared/spec/cli.md`).
//!
//! * [`CliError::BadInput`] → exit 2: unreadable file, malformed CSV, missing
//!   column, non-finite number, non-increasing time, an invalid flag value.
//! * [`CliError::Internal`] → exit 1: anything that is our fault.
//! * [`CliError::RobotFailure`] → exit 1: the robot (an external plant)
//!   broke its protocol or failed; the JSON on stdout says where.
//! * [`CliError::SafetyStop`] → exit 3: a device session ended in a safe
//!   stop (the safety function worked; the JSON on stdout says why).
//!
//! The message is printed as one line on stderr; it names the file and line
//! where the input is at fault.

/// A failure of one `limb` invocation.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// The user's input is at fault (exit code 2).
    #[error("{0}")]
    BadInput(String),
    /// Limb itself failed (exit code 1).
    #[error("internal error: {0}")]
    Internal(String),
    /// The robot failed mid-session (exit code 1).
    #[error("robot failure: {0}")]
    RobotFailure(String),
    /// A device session ended in a safe stop (exit code 3).
    #[error("safe stop: {0}")]
    SafetyStop(String),
}

impl CliError {
    /// The process exit code for this error.
    pub fn exit_code(&self) -> i32 {
        match self {
            CliError::BadInput(_) => 2,
            CliError::Internal(_) | CliError::RobotFailure(_) => 1,
            CliError::SafetyStop(_) => 3,
        }
    }
}

/// Prints exactly one JSON document on stdout, or fails without printing.
pub fn print_json<T: serde::Serialize>(value: &T) -> Result<(), CliError> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|error| CliError::Internal(format!("serialising JSON: {error}")))?;
    emit(&(text + "\n"))
}

/// Writes `text` to stdout in one piece. A reader that went away (broken
/// pipe, as in `limb … | head`) is not an error; any other write failure is.
pub fn emit(text: &str) -> Result<(), CliError> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(error) if error.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(CliError::Internal(format!("writing to stdout: {error}")))
        }
        _ => Ok(()),
    }
}
