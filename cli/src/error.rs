//! Errors of the `limb` command and their exit codes (`../shared/spec/cli.md`).
//!
//! * [`CliError::BadInput`] → exit 2: unreadable file, malformed CSV, missing
//!   column, non-finite number, non-increasing time, an invalid flag value.
//! * [`CliError::Internal`] → exit 1: anything that is our fault.
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
}

impl CliError {
    /// The process exit code for this error.
    pub fn exit_code(&self) -> i32 {
        match self {
            CliError::BadInput(_) => 2,
            CliError::Internal(_) => 1,
        }
    }
}

/// Prints exactly one JSON document on stdout, or fails without printing.
pub fn print_json<T: serde::Serialize>(value: &T) -> Result<(), CliError> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|error| CliError::Internal(format!("serialising JSON: {error}")))?;
    println!("{text}");
    Ok(())
}
