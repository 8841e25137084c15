//! What can go wrong with a plant, each with a stable snake_case code.

/// Why a plant's session ended as a robot failure.
///
/// Every variant names the plant's line (1 = the handshake, counted over
/// the lines the plant sent) where the fault was seen, through
/// [`PlantError`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Fault {
    /// The program could not be started or the address not reached.
    #[error("cannot reach the plant: {0}")]
    Unreachable(String),
    /// Reading or writing the byte stream failed.
    #[error("plant I/O: {0}")]
    Io(String),
    /// The line is not a JSON object.
    #[error("not a JSON object: {0}")]
    Malformed(String),
    /// The line is longer than [`crate::wire::MAX_LINE`] bytes.
    #[error("line longer than {0} bytes")]
    LineTooLong(usize),
    /// A required key is absent.
    #[error("missing field `{0}`")]
    MissingField(String),
    /// A number field holds NaN or an infinity.
    #[error("field `{0}` is not finite")]
    NonFinite(String),
    /// A field has the wrong JSON type (a string in a number field).
    #[error("field `{field}` is not {expected}")]
    WrongType {
        /// The field.
        field: String,
        /// What it must be.
        expected: &'static str,
    },
    /// The handshake is not `limb-plant/1`, or its `dt` is unusable.
    #[error("handshake refused: {0}")]
    Handshake(String),
    /// A frame's truth names differ from the handshake's.
    #[error("truth differs from the handshake: {0}")]
    TruthMismatch(String),
    /// A frame's `t` does not increase.
    #[error("t = {t} does not increase (previous frame t = {previous})")]
    TimeNotIncreasing {
        /// This frame's stamp [s].
        t: f64,
        /// The previous frame's stamp [s].
        previous: f64,
    },
    /// A message this version does not know (no `frame`, `end`).
    #[error("unknown message (keys: {0})")]
    UnknownMessage(String),
    /// The stream closed before the session ended.
    #[error("end of stream before the session ended")]
    EndOfStream,
    /// The plant did not send its next line in time.
    #[error("no line within the timeout of {0} s")]
    Timeout(f64),
    /// The plant's program exited with a failure status after the session.
    #[error("the plant exited with {0}")]
    ExitStatus(String),
}

impl Fault {
    /// Stable snake_case code of the fault (JSON `robot_error.code`).
    pub const fn code(&self) -> &'static str {
        match self {
            Fault::Unreachable(_) => "unreachable",
            Fault::Io(_) => "io",
            Fault::Malformed(_) => "malformed_line",
            Fault::LineTooLong(_) => "line_too_long",
            Fault::MissingField(_) => "missing_field",
            Fault::NonFinite(_) => "non_finite",
            Fault::WrongType { .. } => "wrong_type",
            Fault::Handshake(_) => "handshake_refused",
            Fault::TruthMismatch(_) => "truth_mismatch",
            Fault::TimeNotIncreasing { .. } => "time_not_increasing",
            Fault::UnknownMessage(_) => "unknown_message",
            Fault::EndOfStream => "end_of_stream",
            Fault::Timeout(_) => "timeout",
            Fault::ExitStatus(_) => "exit_status",
        }
    }
}

/// A [`Fault`] at a line of the plant's stream.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("plant line {line}: {fault}")]
pub struct PlantError {
    /// The plant's line the fault was seen on (1 = handshake; 0 = before
    /// any line).
    pub line: u64,
    /// What was wrong.
    pub fault: Fault,
}
