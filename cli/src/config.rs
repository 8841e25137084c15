//! `limb config`: prints the kernel's embedded default configuration (gains,
//! limits, estimation motion, validator ranges), SI units, frame S.

use crate::error::{print_json, CliError};
use limb_kernel::KernelConfig;

/// Prints the default configuration as JSON.
pub fn run() -> Result<(), CliError> {
    let config = KernelConfig::default();
    config
        .check()
        .map_err(|error| CliError::Internal(format!("default configuration invalid: {error}")))?;
    print_json(&config)
}
