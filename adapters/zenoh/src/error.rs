//! Errors of the adapter (not of the kernel: those are refusals and stops).

use limb_kernel::config::ConfigError;

/// What went wrong setting up or running the adapter.
#[derive(Debug, thiserror::Error)]
pub enum AdapterError {
    /// The robot id is not one key-expression chunk.
    #[error("robot id {0:?} must be non-empty ASCII letters, digits, '-' or '_'")]
    RobotId(String),
    /// The kernel configuration failed its check.
    #[error("kernel configuration refused: {0}")]
    KernelConfig(ConfigError),
    /// The control period or another adapter setting is unusable.
    #[error("adapter setting refused: {0}")]
    Setting(&'static str),
    /// Zenoh refused a configuration value or an operation.
    #[cfg(feature = "link")]
    #[error("zenoh: {0}")]
    Zenoh(#[from] zenoh::Error),
    /// A message could not be encoded or decoded.
    #[error(transparent)]
    Wire(#[from] crate::wire::WireError),
    /// A thread could not be started.
    #[error("thread: {0}")]
    Thread(#[from] std::io::Error),
    /// The control loop thread panicked (a bug: the loop has no panicking
    /// path on purpose).
    #[error("the control loop panicked")]
    LoopPanicked,
    /// The robot's I/O failed and ended the session.
    #[error("robot: {0}")]
    Robot(String),
    /// No answer arrived in time.
    #[error("timed out waiting for {0}")]
    Timeout(&'static str),
}
