//! The command hash: FNV-1a (64 bit) over every command the kernel
//! issued, each number taken as its IEEE-754 bit pattern: two sessions with
//! the same hash issued the same commands bit for bit (up to a 2⁻⁶⁴
//! collision). The session loop ([`crate::run`]) keeps it; the digest
//! ([`crate::digest`]) prints it.

use limb_kernel::Command;

/// FNV-1a (64 bit) over commands, field by field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CommandHash(u64);

impl Default for CommandHash {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl CommandHash {
    fn byte(&mut self, byte: u8) {
        self.0 = (self.0 ^ u64::from(byte)).wrapping_mul(0x0000_0100_0000_01b3);
    }

    fn number(&mut self, value: f64) {
        for byte in value.to_bits().to_le_bytes() {
            self.byte(byte);
        }
    }

    /// Adds `command`: state, mode, whether a set-point is present, the
    /// set-point's pose, velocity and acceleration (x, z, psi), the wrench
    /// (fx, fz, ty), the four saturation flags and, in SafeStop only, the
    /// stop category's code (so the hash of a session that never stops is
    /// the one it had before stop categories).
    pub fn push(&mut self, command: &Command) {
        self.byte(command.state as u8);
        self.byte(command.mode as u8);
        match &command.set_point {
            Some(s) => {
                self.byte(1);
                let (p, v, a) = (s.pose, s.velocity, s.acceleration);
                for value in [p.x, p.z, p.psi, v.x, v.z, v.psi, a.x, a.z, a.psi] {
                    self.number(value);
                }
            }
            None => self.byte(0),
        }
        let w = command.wrench;
        for value in [w.fx, w.fz, w.ty] {
            self.number(value);
        }
        let s = command.saturation;
        for flag in [s.force, s.torque, s.speed, s.non_finite] {
            self.byte(u8::from(flag));
        }
        if let Some(category) = command.stop {
            self.byte(category.code());
        }
    }

    /// The hash so far.
    pub fn value(&self) -> u64 {
        self.0
    }
}

#[cfg(test)]
mod tests {
    use super::CommandHash;
    use limb_kernel::geometry::{Pose, Wrench};
    use limb_kernel::impedance::Saturation;
    use limb_kernel::motion::SetPoint;
    use limb_kernel::{Command, CommandMode, StateKind, StopCategory};

    fn command(x: f64) -> Command {
        Command {
            state: StateKind::Grasp,
            mode: CommandMode::Hold,
            set_point: Some(SetPoint::hold(Pose::new(x, 0.0, 0.0))),
            wrench: Wrench::ZERO,
            saturation: Saturation::default(),
            stop: None,
        }
    }

    fn hash(commands: &[Command]) -> u64 {
        let mut h = CommandHash::default();
        commands.iter().for_each(|c| h.push(c));
        h.value()
    }

    /// REQ-DET-001: the command hash that compares host and target sessions
    /// changes with any bit of any command and with their order.
    #[test]
    fn the_hash_sees_every_bit_and_the_order() {
        let (a, b) = (command(0.1), command(0.2));
        assert_ne!(hash(&[a, b]), hash(&[b, a]));
        // One ulp apart.
        assert_ne!(
            hash(&[a]),
            hash(&[command(f64::from_bits(0.1f64.to_bits() + 1))])
        );
        assert_ne!(
            hash(&[a]),
            hash(&[Command {
                set_point: None,
                ..a
            }])
        );
        let mut saturated = a;
        saturated.saturation.speed = true;
        assert_ne!(hash(&[a]), hash(&[saturated]));
        let stops = StopCategory::ALL.map(|category| {
            hash(&[Command {
                state: StateKind::SafeStop,
                mode: CommandMode::Stop,
                stop: Some(category),
                ..a
            }])
        });
        assert!(stops[0] != stops[1] && stops[1] != stops[2] && stops[0] != stops[2]);
        assert_eq!(hash(&[a, b]), hash(&[a, b]));
    }
}
