//! AREBO as the robot of a `limb-session` session: stream frames in as
//! kernel frames, kernel commands out as torque targets. Translation only;
//! the loop, the clock, the watchdog and the supervisor are the session's.
//!
//! # Theory of operation
//! The kernel's arm is the planar two-link arm of `plant.md`, estimated by
//! lifting the wrist; the cuff holds the wrist, its roll axis z_R5 along
//! the forearm (from the elbow toward the hand). Frame S
//! ([`SagittalFrame`]): origin the cuff centre at the first frame, +z
//! up (= z_R0), +x horizontal toward the shoulder at `heading` about z_R0,
//! +y = z × x (lateral). Per stream frame:
//! 1. counts → θ1..θ5 ([`crate::encoder`]) → cuff centre p_r (R0) and the
//!    forearm axis z_R5 ([`crate::kinematics::frame_5`]);
//! 2. grasp pose in S: (x, z) of p_r, ψ = atan2(a_z, −a_x) of the forearm
//!    axis a in S (ψ > 0 when the hand is above the elbow), lateral y;
//! 3. wrench in S: the torque sensors less the robot's gravity torques
//!    (τ_int = τ_r − τ_g), f = J_a^{-T} τ_int is the force the robot puts
//!    on the cuff (R0); the arm's force on the robot, −f in S, is (fx, fz);
//!    ty = 0 (the spherical joint carries no moment);
//! 4. the stamp is the device's run time since its first frame, as the
//!    device gave it; the arrival is the host's read time (a backlog read
//!    after a host stall, or a run time that stopped, ages the frames
//!    against the session clock: the kernel's watchdog decides), or for a
//!    simulated device whose clock is the simulation's, the stamp itself
//!    ([`ArrivalClock::Robot`]: a loaded test machine's stalls are not the
//!    device's);
//! 5. the device's status and error bits ([`crate::safety::check_device`],
//!    torque mode expected) end the session with their named verdict,
//!    motors off ([`AreboStop::Device`]).
//!
//! The kernel's command → torque target: its wrench (fx, fz) at the grasp,
//! frame S, → R0 → τ_d = J_aᵀ f (the target is the interaction torque the
//! device adds to its gravity compensation). ty is dropped: three actuated
//! joints place a force at the spherical joint, never a moment.
//!
//! Stops ([`limb_kernel::stop`]): in a hold the kernel's wrench is the
//! impedance law's about its held set-point, so the device keeps its
//! gravity compensation plus the held arm's weight; in a ramp-down that
//! wrench falls to zero over 1 s, leaving gravity compensation; only a
//! motors-off stop switches the motors off (control type 0: the device's
//! ≈ 32 N and the arm then rest on the person). At the end of a session
//! ([`AreboRobot::finish`]) the device is handed to its own fallback,
//! gravity compensation, unless the kernel's last command was motors off.

use crate::control::{interaction_force, GravityParameters};
use crate::encoder::{actuated_angles, Encoder};
use crate::kinematics::{self, ActuatedAngles, JointAngles};
use crate::link::{LinkError, Received, Session, SessionState, StopCause};
use crate::protocol::{Command as DeviceCommand, ControlType};
use crate::safety::{check_device, AreboViolation};
use crate::sagittal::SagittalFrame;
use limb_kernel::geometry::Wrench;
use limb_kernel::{Command, PathSample, StopCategory};
use limb_session::{ArrivalClock, Frame, Robot, Sensed};
use nalgebra::Vector3;
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// The forearm axis z_R5 (R0, unit) of a frame's counts.
pub fn forearm_axis(counts: &[i32; 5]) -> Vector3<f64> {
    let [t1, t2, t3] = actuated_angles(counts).0;
    let t4 = Encoder::Distal.angle(counts[3]);
    let t5 = Encoder::Distal.angle(counts[4]);
    let (rotation, _) = kinematics::frame_5(&JointAngles([t1, t2, t3, t4, t5, 0.0]));
    rotation * Vector3::z()
}

/// Why an AREBO session ended early.
#[derive(Debug, thiserror::Error)]
pub enum AreboStop {
    /// The device's status or error bits (motors commanded off).
    #[error("device: {0:?}")]
    Device(AreboViolation),
    /// The link stopped (port lost, control type not confirmed; motors
    /// commanded off).
    #[error("link: {0:?}")]
    Link(StopCause),
    /// The port failed.
    #[error(transparent)]
    Io(#[from] LinkError),
}

impl AreboStop {
    /// The verdict behind the stop, when it has one.
    pub fn violation(&self) -> Option<AreboViolation> {
        match self {
            AreboStop::Device(v) | AreboStop::Link(StopCause::Violation(v)) => Some(*v),
            AreboStop::Io(LinkError::Stopped(StopCause::Violation(v))) => Some(*v),
            _ => None,
        }
    }
}

/// What the translation counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AreboRecord {
    /// Stream frames handed to the kernel.
    pub frames: u64,
    /// Polls that brought no frame (silences shown to the kernel).
    pub silent_polls: u64,
    /// Commands whose torque target could not be formed (held at zero).
    pub held: u64,
    /// Kernel stop commands by category code (1 hold, 2 ramp_down,
    /// 3 motors_off; index 0 unused).
    pub stop_commands: [u64; 4],
    /// True once a motors-off stop switched the motors off.
    pub motors_off: bool,
}

/// AREBO behind a serial [`Session`], in torque mode.
pub struct AreboRobot {
    session: Session,
    heading: f64,
    gravity: GravityParameters,
    clock: ArrivalClock,
    frame: Option<SagittalFrame>,
    time_origin: Option<f64>,
    /// The last frame's stamp since the first [s].
    last_time: f64,
    pending: VecDeque<Received>,
    last_q: Option<ActuatedAngles>,
    end: Option<Instant>,
    record: AreboRecord,
}

impl AreboRobot {
    /// Puts the device behind `session` in torque mode (zero target) and
    /// makes it a session robot whose frame S has its x axis at `heading`
    /// [rad] about z_R0; the session ends after `duration` (never when
    /// `None`).
    ///
    /// # Errors
    /// [`LinkError`] when the device does not confirm torque mode.
    pub fn start(
        mut session: Session,
        heading: f64,
        gravity: GravityParameters,
        duration: Option<Duration>,
    ) -> Result<Self, LinkError> {
        session.send(DeviceCommand::SetControlTarget([0.0; 3]))?;
        let pending = session.set_control(ControlType::Torque)?.into();
        Ok(Self {
            session,
            heading,
            gravity,
            clock: ArrivalClock::Host,
            frame: None,
            time_origin: None,
            last_time: 0.0,
            pending,
            last_q: None,
            end: duration.and_then(|d| Instant::now().checked_add(d)),
            record: AreboRecord::default(),
        })
    }

    /// Reads arrivals on `clock` (the default is [`ArrivalClock::Host`]).
    pub fn arrival_clock(&mut self, clock: ArrivalClock) {
        self.clock = clock;
    }

    /// What the translation counted.
    pub fn record(&self) -> AreboRecord {
        self.record
    }

    /// Frame S, once recorded.
    pub fn sagittal_frame(&self) -> Option<&SagittalFrame> {
        self.frame.as_ref()
    }

    /// The link (its counters, its state).
    pub fn session(&self) -> &Session {
        &self.session
    }

    /// Motors off (a motors-off stop, or a caller that wants it).
    pub fn switch_off(&mut self) {
        self.record.motors_off = true;
        let _ = self
            .session
            .send(DeviceCommand::SetControlType(ControlType::Off));
    }

    /// The end of a session: motors off after a motors-off stop, else the
    /// link's end ([`Session::finish`]: gravity compensation, or the
    /// category of the link's own stop).
    pub fn finish(&mut self) {
        if self.record.motors_off {
            self.switch_off();
        } else {
            self.session.finish();
        }
    }

    /// The kernel frame of one stream frame (recording frame S at the
    /// first), or the device's verdict.
    fn frame(&mut self, received: &Received) -> Result<Frame, AreboViolation> {
        let t = &received.telemetry;
        check_device(t.status, t.error, ControlType::Torque)?;
        let q = actuated_angles(&t.counts);
        let centre = kinematics::endpoint(q);
        let heading = self.heading;
        let frame = *self
            .frame
            .get_or_insert_with(|| SagittalFrame::new(centre, heading));
        let (pose, lateral) = frame.pose(&centre, &forearm_axis(&t.counts));
        let sensed = Vector3::new(
            f64::from(t.torques[0]),
            f64::from(t.torques[1]),
            f64::from(t.torques[2]),
        );
        let wrench = interaction_force(q, &(sensed - self.gravity.torques(q)))
            .map(|on_cuff| frame.in_s(&-on_cuff))
            .map_or(
                Wrench {
                    fx: f64::NAN,
                    fz: f64::NAN,
                    ty: f64::NAN,
                },
                |f| Wrench {
                    fx: f.x,
                    fz: f.z,
                    ty: 0.0,
                },
            );
        self.last_q = Some(q);
        let stamp = f64::from(t.run_time_ms) * 1e-3;
        let origin = *self.time_origin.get_or_insert(stamp);
        let time = stamp - origin;
        self.last_time = time;
        Ok(Frame {
            sample: PathSample { time, pose, wrench },
            lateral: Some(lateral),
            arrival: match self.clock {
                ArrivalClock::Host => received.read_at,
                ArrivalClock::Robot => time,
            },
            following: true,
        })
    }

    /// The device-side stop of `violation`: motors off, the session's end.
    fn device_stop(&mut self, violation: AreboViolation) -> AreboStop {
        self.session.stop(StopCause::Violation(violation));
        AreboStop::Device(violation)
    }
}

impl Robot for AreboRobot {
    type Error = AreboStop;

    fn sense(&mut self) -> Result<Sensed, AreboStop> {
        loop {
            if self.end.is_some_and(|end| Instant::now() >= end) {
                self.finish();
                return Ok(Sensed::Ended);
            }
            if let SessionState::SafeStop(cause) = self.session.state() {
                return Err(AreboStop::Link(cause));
            }
            if let Some(received) = self.pending.pop_front() {
                self.record.frames += 1;
                return match self.frame(&received) {
                    Ok(frame) => Ok(Sensed::Frame(frame)),
                    Err(violation) => Err(self.device_stop(violation)),
                };
            }
            self.pending.extend(self.session.poll());
            if self.pending.is_empty() && self.session.state() == SessionState::Running {
                self.record.silent_polls += 1;
                // On the device's clock no time passes while it sends
                // nothing; the link's own freshness check (host time) ends
                // a session whose device has died.
                return Ok(Sensed::Silent(match self.clock {
                    ArrivalClock::Host => self.session.now(),
                    ArrivalClock::Robot => self.last_time,
                }));
            }
        }
    }

    fn actuate(&mut self, command: &Command) -> Result<(), AreboStop> {
        if let Some(category) = command.stop {
            self.record.stop_commands[usize::from(category.code()).min(3)] += 1;
        }
        if command.stop == Some(StopCategory::MotorsOff) || self.record.motors_off {
            if !self.record.motors_off {
                self.switch_off();
            }
            return Ok(());
        }
        let torques = match (self.frame, self.last_q) {
            (Some(frame), Some(q)) => kinematics::joint_torques(q, &frame.to_r0(&command.wrench)),
            _ => Vector3::zeros(),
        };
        let target = if torques.iter().all(|t| t.is_finite()) {
            [torques.x as f32, torques.y as f32, torques.z as f32]
        } else {
            self.record.held += 1;
            [0.0; 3]
        };
        self.session
            .send(DeviceCommand::SetControlTarget(target))
            .map_err(AreboStop::Io)
    }
}

impl limb_session::log::Logged for AreboRobot {}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encoder::Encoder;
    use proptest::prelude::*;

    fn frame() -> SagittalFrame {
        SagittalFrame::new(Vector3::new(0.4, 0.1, -0.2), 2.0)
    }

    /// The forearm axis from θ4, θ5 of the counts is R5's z axis.
    #[test]
    fn the_forearm_axis_is_r5_z() {
        let angles = [0.3, 0.5, 0.9, 0.4, -0.6];
        let counts: [i32; 5] = core::array::from_fn(|i| Encoder::MEASURED[i].counts(angles[i]));
        let q: [f64; 5] = core::array::from_fn(|i| Encoder::MEASURED[i].angle(counts[i]));
        let (r, _) = kinematics::frame_5(&JointAngles([q[0], q[1], q[2], q[3], q[4], 0.0]));
        assert!((forearm_axis(&counts) - r * Vector3::z()).norm() < 1e-12);
    }

    /// The configuration CI's proptest drew (t2 0.480, t3 1.978 rad) is
    /// singular: no interaction force, said by `None`, not a panic.
    #[test]
    fn a_singular_configuration_has_no_interaction_force() {
        let q = ActuatedAngles([0.0, 0.480_024_045_361_332_86, 1.977_893_497_222_217_7]);
        let target = kinematics::joint_torques(q, &Vector3::new(1.0, 0.0, 1.0));
        assert_eq!(interaction_force(q, &target), None);
    }

    proptest! {
        /// A kernel wrench goes out as the torques of that force in R0
        /// (ty dropped): the device's force from the target is the
        /// wrench's (fx, fz) in S.
        #[test]
        fn a_kernel_wrench_is_the_force_the_target_makes(
            fx in -50.0..50.0f64, fz in -50.0..50.0f64, ty in -5.0..5.0f64,
            t1 in -1.0..1.0f64, t2 in -0.5..0.8f64, t3 in 0.4..2.0f64,
        ) {
            let s = frame();
            let q = ActuatedAngles([t1, t2, t3]);
            let wrench = Wrench { fx, fz, ty };
            let target = kinematics::joint_torques(q, &s.to_r0(&wrench));
            // Near a singularity (seen in CI: t2 0.48, t3 1.978 rad) there
            // is no force to recover, and `None` says so.
            let Some(force) = interaction_force(q, &target) else {
                let j = kinematics::jacobian(q);
                let actuated: nalgebra::Matrix3<f64> = j.fixed_view::<3, 3>(0, 0).into_owned();
                prop_assert!(actuated.determinant().abs() < 1e-6);
                return Ok(());
            };
            let back = s.in_s(&force);
            prop_assert!((back.x - fx).abs() < 1e-6 && (back.z - fz).abs() < 1e-6);
            prop_assert!(back.y.abs() < 1e-6);
        }
    }
}
