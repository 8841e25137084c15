//! Encoder conversions (paper 2.2.2, Table 2).
//!
//! θ1..θ3 are read on the motor shafts (4096 counts per motor turn) behind
//! 53:1, 43:1, 43:1 gearboxes; θ4, θ5 on the joints (1000 counts per
//! turn); θ6 is not measured. One count is therefore 2π / (4096 · 53) ≈
//! 28.9 µrad on θ1, 2π / (4096 · 43) ≈ 35.7 µrad on θ2, θ3 and 6.28 mrad
//! (0.36°) on θ4, θ5. Converting an angle to counts rounds to the nearest
//! count, which is the quantisation a real read-out applies.

use crate::kinematics::{self, ActuatedAngles};
use nalgebra::Vector3;

/// Motor encoder resolution [counts per motor turn].
pub const MOTOR_COUNTS_PER_TURN: f64 = 4096.0;
/// Gear ratios of joints 1..3 (motor turns per joint turn).
pub const GEAR_RATIOS: [f64; 3] = [53.0, 43.0, 43.0];
/// Distal encoder resolution on θ4, θ5 [counts per joint turn].
pub const DISTAL_COUNTS_PER_TURN: f64 = 1000.0;

/// A measured joint: which counts-per-joint-turn applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoder {
    /// Actuated joint 1, 2 or 3 (index 0..=2), motor-side encoder.
    Actuated(usize),
    /// Unactuated joint 4 or 5, joint-side encoder.
    Distal,
}

impl Encoder {
    /// The five measured joints θ1..θ5, in order.
    pub const MEASURED: [Encoder; 5] = [
        Encoder::Actuated(0),
        Encoder::Actuated(1),
        Encoder::Actuated(2),
        Encoder::Distal,
        Encoder::Distal,
    ];

    /// Counts per joint turn.
    pub fn counts_per_turn(self) -> f64 {
        match self {
            Encoder::Actuated(i) => {
                MOTOR_COUNTS_PER_TURN * GEAR_RATIOS.get(i).copied().unwrap_or(1.0)
            }
            Encoder::Distal => DISTAL_COUNTS_PER_TURN,
        }
    }

    /// One count [rad].
    pub fn resolution(self) -> f64 {
        2.0 * core::f64::consts::PI / self.counts_per_turn()
    }

    /// Joint angle [rad] of a count.
    pub fn angle(self, counts: i32) -> f64 {
        f64::from(counts) * self.resolution()
    }

    /// Nearest count of a joint angle [rad], saturated to the i32 range
    /// (NaN gives 0: the caller's finiteness check is upstream).
    pub fn counts(self, angle: f64) -> i32 {
        // `as` saturates and maps NaN to 0, which is what we want here.
        libm::round(angle / self.resolution()) as i32
    }

    /// The angle as the encoder reports it [rad] (quantised).
    pub fn quantise(self, angle: f64) -> f64 {
        self.angle(self.counts(angle))
    }
}

/// Gearbox backlash of θ1..θ3 [rad] (paper 2.2.2: about 1°).
pub const NOMINAL_BACKLASH: [f64; 3] = [
    core::f64::consts::PI / 180.0,
    core::f64::consts::PI / 180.0,
    core::f64::consts::PI / 180.0,
];

/// Inverse of a dead-band backlash between link and motor-side encoder.
///
/// A link moving in + drags the motor side half the play behind it, so
/// link ≈ motor + play/2 · (direction of the last motor movement). After a
/// reversal the motor side stands still until the link has crossed the
/// play, and the estimate is off by up to the play until it moves again;
/// everywhere else the play is removed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BacklashCompensator {
    play: [f64; 3],
    last: Option<[f64; 3]>,
    direction: [f64; 3],
    moved: [bool; 3],
}

impl BacklashCompensator {
    /// A compensator for `play` [rad] on θ1..θ3 (zero: pass-through).
    pub const fn new(play: [f64; 3]) -> Self {
        Self {
            play,
            last: None,
            direction: [0.0; 3],
            moved: [false; 3],
        }
    }

    /// Link angles [rad] from the motor-side angles [rad] of this sample.
    pub fn link_angles(&mut self, motor: [f64; 3]) -> [f64; 3] {
        if let Some(last) = self.last {
            for (((direction, moved), now), before) in self
                .direction
                .iter_mut()
                .zip(self.moved.iter_mut())
                .zip(motor)
                .zip(last)
            {
                *moved = now != before;
                if now > before {
                    *direction = 1.0;
                } else if now < before {
                    *direction = -1.0;
                }
            }
        }
        self.last = Some(motor);
        let mut link = motor;
        for ((angle, play), direction) in link.iter_mut().zip(self.play).zip(self.direction) {
            *angle += 0.5 * play * direction;
        }
        link
    }

    /// True unless a joint with play may be inside it: every joint with
    /// play either moved in the last sample (its play is closed and the
    /// estimate exact) or has not moved since the start (its side of the
    /// play is unknown, so no compensation is applied and it stays off by
    /// at most half the play; a pose that holds a joint still, such as
    /// θ1 in a flexion-only movement, can still be calibrated). A joint
    /// that moved before and stands still now may be reversing inside its
    /// play: calibration leaves such samples out.
    pub fn settled(&self) -> bool {
        self.moved
            .iter()
            .zip(self.play)
            .zip(self.direction)
            .all(|((moved, play), direction)| *moved || play == 0.0 || direction == 0.0)
    }

    /// The endpoint estimate [m, frame R0] of one frame's encoder counts
    /// θ1..θ5: counts → motor-side angles → backlash compensation → forward
    /// kinematics.
    pub fn endpoint(&mut self, counts: &[i32; 5]) -> Vector3<f64> {
        kinematics::endpoint(ActuatedAngles(self.link_angles(actuated_angles(counts).0)))
    }
}

/// θ1..θ3 [rad] from encoder counts θ1..θ5 (motor side, no backlash
/// correction).
pub fn actuated_angles(counts: &[i32; 5]) -> ActuatedAngles {
    ActuatedAngles([0, 1, 2].map(|i| Encoder::Actuated(i).angle(counts[i])))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Quantisation error is at most half a count on every joint.
        #[test]
        fn quantisation_within_half_count(angle in -3.2f64..3.2, joint in 0usize..5) {
            let encoder = Encoder::MEASURED[joint];
            let error = libm::fabs(encoder.quantise(angle) - angle);
            prop_assert!(error <= 0.5 * encoder.resolution() + 1e-15);
        }
    }

    #[test]
    fn compensation_removes_the_play_while_moving() {
        let mut compensator = BacklashCompensator::new([0.02; 3]);
        // Link moving +: the motor side trails by 0.01.
        compensator.link_angles([0.0; 3]);
        let link = compensator.link_angles([0.05; 3]);
        assert!((link[0] - 0.06).abs() < 1e-12);
        let link = compensator.link_angles([0.04; 3]);
        assert!((link[1] - 0.03).abs() < 1e-12);
    }

    /// Finding 9 of issue 18: a joint that never moves (θ1 in a
    /// flexion-only movement) does not make every sample "unsettled"; a
    /// joint that stops after moving (a reversal inside the play) does.
    #[test]
    fn a_joint_that_never_moves_keeps_the_samples() {
        let mut compensator = BacklashCompensator::new([0.02; 3]);
        compensator.link_angles([0.0; 3]);
        let mut kept = 0;
        for i in 1..=10 {
            let step = f64::from(i) * 0.001;
            compensator.link_angles([0.0, step, step]);
            kept += usize::from(compensator.settled());
        }
        assert_eq!(kept, 10);
        compensator.link_angles([0.0, 0.01, 0.011]);
        assert!(!compensator.settled(), "θ2 stands still after moving");
    }

    #[test]
    fn resolutions_match_table_2() {
        assert!((Encoder::Actuated(0).resolution() - 2.894e-5).abs() < 1e-8);
        assert!((Encoder::Actuated(1).resolution() - 3.567e-5).abs() < 1e-8);
        assert!((Encoder::Distal.resolution() - 6.283e-3).abs() < 1e-6);
    }
}
