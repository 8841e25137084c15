//! Key expressions of one robot, all under `limb/<robot-id>/@v2/`.
//!
//! | key (after the prefix) | direction | QoS | payload |
//! |---|---|---|---|
//! | `telemetry/event` | kernel → | reliable, Block | [`crate::wire::EventMessage`] |
//! | `telemetry/sample` | kernel → | best effort, Drop | [`crate::wire::SampleMessage`] |
//! | `telemetry/link` | kernel → | reliable, Block | [`crate::wire::LinkMessage`] |
//! | `model/arm` | kernel → (put on change, and queryable) | reliable, Block | [`crate::wire::ArmModel`] |
//! | `state` | queryable | — | [`crate::wire::StateSnapshot`] |
//! | `config` | queryable | — | `KernelConfig` |
//! | `cmd/request` | → kernel | reliable, Block, signed | [`crate::wire::CommandMessage`] |
//! | `cmd/estop` | → kernel | reliable, Block, express, priority RealTime, unsigned | [`crate::wire::EmergencyStopMessage`] |
//! | `ack/command` | kernel → | reliable, Block | [`crate::wire::Ack`] |
//! | `alive/supervisor` | → kernel | best effort, signed | [`crate::wire::Heartbeat`] |
//! | `alive/kernel` | kernel → | best effort | [`crate::wire::KernelStatus`] |
//!
//! The `@v2` chunk seals the namespace: a wildcard such as `limb/*/**` or
//! `limb/<robot-id>/**` does not match into it (subscribe to
//! `limb/<robot-id>/@v2/**`), and an incompatible encoding gets the next
//! `@vN`. `@v1` (before `PROTOCOL.md`) spelled kernel values by their Rust
//! names and counted heartbeats from 0; see `PROTOCOL.md`, "Changes".

use crate::error::AdapterError;

/// The key expressions of one robot.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Keys {
    prefix: String,
}

impl Keys {
    /// The keys of robot `robot_id`: one key-expression chunk of letters,
    /// digits, `-` or `_`.
    ///
    /// # Errors
    /// [`AdapterError::RobotId`] for an empty id or any other character.
    pub fn new(robot_id: &str) -> Result<Self, AdapterError> {
        let valid = !robot_id.is_empty()
            && robot_id
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
        if !valid {
            return Err(AdapterError::RobotId(robot_id.to_owned()));
        }
        Ok(Self {
            prefix: format!("limb/{robot_id}/@v2"),
        })
    }

    /// `limb/<robot-id>/@v2/<suffix>`.
    pub fn key(&self, suffix: &str) -> String {
        format!("{}/{suffix}", self.prefix)
    }

    /// Transition and refusal events (reliable).
    pub fn event(&self) -> String {
        self.key("telemetry/event")
    }

    /// Pose, wrench and command samples (best effort).
    pub fn sample(&self) -> String {
        self.key("telemetry/sample")
    }

    /// Supervisor-link events: lost, back (reliable).
    pub fn link(&self) -> String {
        self.key("telemetry/link")
    }

    /// The validated arm model.
    pub fn arm(&self) -> String {
        self.key("model/arm")
    }

    /// The state queryable.
    pub fn state(&self) -> String {
        self.key("state")
    }

    /// The configuration queryable.
    pub fn config(&self) -> String {
        self.key("config")
    }

    /// Signed supervisory requests.
    pub fn request(&self) -> String {
        self.key("cmd/request")
    }

    /// Emergency stop (unsigned: anyone on the network may stop the robot).
    pub fn emergency_stop(&self) -> String {
        self.key("cmd/estop")
    }

    /// Acknowledgements of commands.
    pub fn ack(&self) -> String {
        self.key("ack/command")
    }

    /// The supervisor's heartbeat.
    pub fn supervisor_alive(&self) -> String {
        self.key("alive/supervisor")
    }

    /// The kernel side's heartbeat and status.
    pub fn kernel_alive(&self) -> String {
        self.key("alive/kernel")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_live_under_the_versioned_prefix() {
        let keys = Keys::new("arm-1").unwrap();
        assert_eq!(keys.request(), "limb/arm-1/@v2/cmd/request");
        assert_eq!(keys.supervisor_alive(), "limb/arm-1/@v2/alive/supervisor");
    }

    #[test]
    fn robot_ids_that_would_change_the_key_space_are_refused() {
        for bad in ["", "a/b", "*", "a**", "@v2", "a b"] {
            assert!(Keys::new(bad).is_err(), "{bad}");
        }
    }
}
