//! A simulated KUKA FRI controller (the robot side), over real UDP, driving
//! the reference plant of `limb-sim` from the client's commands, with
//! seeded fault injection ([`crate::faults`]).
//!
//! Theory of operation, one cycle = one send period:
//! 1. session state: IDLE (fault) → MONITORING_WAIT → MONITORING_READY
//!    after [`SimSettings::ready_after`] answered cycles → COMMANDING_WAIT
//!    after [`SimSettings::command_after`] more cycles with quality ≥ GOOD →
//!    COMMANDING_ACTIVE once the client's reply carries the IPO joint
//!    position (synchronisation). Quality comes from the replies missed in
//!    the last [`QUALITY_WINDOW`] cycles (0: EXCELLENT, ≤ 5: GOOD, ≤ 20:
//!    FAIR, else POOR) or is forced POOR by a fault; below GOOD the overlay
//!    is aborted (back to MONITORING_READY, the robot holds its set-point);
//! 2. the plant is measured; the grasp pose in frame S becomes flange pose
//!    and joint angles (inverse kinematics from the last ones), its wrench
//!    the external joint torques τ = Jᵀ F; one monitoring message is
//!    encoded (time stamp = plant time);
//! 3. the faults of the cycle act on the datagram (drop, delay, duplicate,
//!    reorder, garbage, CRC); the datagrams are sent to the client;
//! 4. the reply to this cycle's counter is awaited until the deadline (next
//!    send tick when paced; `reply_timeout` when unpaced). Replies to other
//!    counters are late and ignored. No reply: the robot holds its last
//!    set-point (a missed cycle);
//! 5. in COMMANDING_ACTIVE the reply moves the robot: joint mode — the
//!    target's flange pose in S is the impedance set-point (velocity by
//!    difference); wrench mode — the robot's Cartesian impedance re-anchored
//!    at the measured pose plus the overlay: set-point = measured pose +
//!    K⁻¹ F, zero velocity;
//! 6. the plant advances one period ([`limb_sim::closed_loop::advance`]).
//!
//! Paced ([`Pacing::RealTime`]), a cycle that starts more than a period late
//! (this process was descheduled) first runs the plant through the whole
//! periods lost, holding its set-point, and stays on its tick grid: the
//! robot's clock keeps wall time, as a real controller's does, and a stall
//! shows as a jump of the stamps (counted in [`SimStats::periods_lost`]).
//!
//! Unpaced ([`Pacing::AsFastAsPossible`]) the next cycle starts as soon as
//! the reply is in; a cycle whose datagram was not delivered lasts one
//! send period of wall time, so a loss burst is silence on the client's
//! clock too.

use std::collections::VecDeque;
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use limb_kernel::geometry::{Pose, PoseRate};
use limb_kernel::motion::SetPoint;
use limb_sim::noise::Gaussian;
use limb_sim::{Plant, PlantParameters};
use nalgebra::Vector6;

use crate::codec::{decode_command, encode_monitoring, EncodeError, MAX_DATAGRAM_BYTES};
use crate::faults::{ActiveFaults, FaultSchedule};
use crate::grasp_frame::GraspFrame;
use crate::kinematics::{forward, inverse, joint_torque_from_wrench};
use crate::messages::{
    ClientCommandMode, ConnectionInfo, ConnectionQuality, ControlMode, FriCommandMessage,
    FriMonitoringMessage, JointValues, MessageHeader, MessageIpoData, MessageMonitorData,
    OverlayType, RobotInfo, SessionState, TimeStamp, MONITORING_MESSAGE_ID,
};
use crate::robot::Overlay;
use crate::session::JointVector;
use crate::version::FriVersion;

/// How long the controller spins for a reply after sending.
pub const SPIN_FOR: Duration = Duration::from_micros(200);
/// Poll interval after [`SPIN_FOR`].
pub const POLL_EVERY: Duration = Duration::from_micros(50);
/// How many recent send times are kept to time late replies.
pub const SENT_MEMORY: usize = 32;
/// Cycles over which missed replies set the connection quality.
pub const QUALITY_WINDOW: usize = 100;
/// A reply synchronises COMMANDING_WAIT when every joint is within this of
/// the IPO position [rad].
const SYNC_TOLERANCE: f64 = 1e-6;
/// Inverse kinematics tolerance (m, rad) and iteration bound of the robot
/// model (the grasp moves ≤ 0.15 mm per cycle: two or three iterations).
const INVERSE_TOLERANCE: f64 = 1e-10;
const INVERSE_ITERATIONS: usize = 10;

/// The iiwa configuration at grasp used by default [rad]: elbow bent, the
/// flange pointing down, away from singularities and joint limits.
pub const DEFAULT_GRASP_JOINTS: JointVector = [0.0, 0.75, 0.0, -1.35, 0.0, 1.04, 0.0];
/// Heading of frame S's x axis in the base by default [rad]: toward the
/// robot base (the person's shoulder lies between wrist and robot).
pub const DEFAULT_HEADING: f64 = core::f64::consts::PI;

/// How the controller paces its cycles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pacing {
    /// One cycle per send period of wall time (a real controller).
    RealTime,
    /// The next cycle as soon as the reply is in (tests).
    AsFastAsPossible,
}

/// Configuration of the simulated controller.
#[derive(Debug, Clone)]
pub struct SimSettings {
    /// Wire version.
    pub version: FriVersion,
    /// Send period [ms] (1..100).
    pub send_period_ms: u32,
    /// Command mode the robot expects.
    pub overlay: Overlay,
    /// Pacing.
    pub pacing: Pacing,
    /// Unpaced: how long to wait for a reply.
    pub reply_timeout: Duration,
    /// Robot joints at grasp [rad].
    pub grasp_joints: JointVector,
    /// Heading of S's x axis about base z [rad].
    pub heading: f64,
    /// Answered cycles in MONITORING_WAIT before MONITORING_READY.
    pub ready_after: u32,
    /// Cycles in MONITORING_READY with quality ≥ GOOD before the overlay
    /// starts (COMMANDING_WAIT).
    pub command_after: u32,
    /// Injected faults.
    pub faults: FaultSchedule,
}

impl SimSettings {
    /// Defaults: 1 ms, joint position, unpaced with a 2 s reply timeout
    /// (unpaced, the robot's clock waits for the client, e.g. for the
    /// kernel's end-of-estimation fit in a debug build),
    /// grasp at [`DEFAULT_GRASP_JOINTS`], 20 + 20 cycles before commanding,
    /// no faults.
    pub fn new(version: FriVersion) -> Self {
        Self {
            version,
            send_period_ms: 1,
            overlay: Overlay::JointPosition,
            pacing: Pacing::AsFastAsPossible,
            reply_timeout: Duration::from_secs(2),
            grasp_joints: DEFAULT_GRASP_JOINTS,
            heading: DEFAULT_HEADING,
            ready_after: 20,
            command_after: 20,
            faults: FaultSchedule::default(),
        }
    }

    /// The send period [s].
    pub fn period(&self) -> f64 {
        f64::from(self.send_period_ms.clamp(1, 100)) * 1e-3
    }
}

/// A failure of the simulated controller's own I/O or encoding.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// Socket error.
    #[error("simulated controller socket: {0}")]
    Io(#[from] std::io::Error),
    /// A monitoring message could not be encoded.
    #[error("simulated controller encode: {0}")]
    Encode(#[from] EncodeError),
    /// The plant could not be built.
    #[error("simulated controller plant: {0}")]
    Plant(String),
}

/// Counts of one run.
#[derive(Debug, Clone, Default)]
pub struct SimStats {
    /// Cycles run.
    pub cycles: u64,
    /// Cycles per session state (index = state value).
    pub state_cycles: [u64; 5],
    /// Monitoring datagrams sent (duplicates included).
    pub datagrams_sent: u64,
    /// Monitoring datagrams dropped by a fault.
    pub datagrams_dropped: u64,
    /// Garbage datagrams sent.
    pub garbage_sent: u64,
    /// Replies to the cycle's own counter before the deadline.
    pub replies_on_time: u64,
    /// Non-IDLE cycles without a reply before the deadline.
    pub missed_cycles: u64,
    /// Missed cycles whose monitoring datagram had been delivered intact.
    pub missed_with_delivery: u64,
    /// Replies to another counter (late, duplicated) or undecodable.
    pub stray_replies: u64,
    /// Of the stray replies, those answering one of the last
    /// [`SENT_MEMORY`] monitoring datagrams after its deadline.
    pub late_replies: u64,
    /// Replies carrying a non-finite number (must stay 0).
    pub non_finite_replies: u64,
    /// Overlay aborts (COMMANDING_* → MONITORING_READY on quality).
    pub overlay_aborts: u64,
    /// Entries into COMMANDING_ACTIVE.
    pub commanding_entries: u64,
    /// Largest first-target jump from the IPO position at an entry [rad].
    pub max_entry_jump: f64,
    /// Round trips send → reply [µs], on-time and late replies.
    pub round_trips_us: Vec<u32>,
    /// Inverse kinematics failures of the robot model (joints kept).
    pub inverse_failures: u64,
    /// Paced: whole send periods this process lost to overruns (it was
    /// descheduled), through which the robot's time ran on holding its
    /// set-point, as a real controller's clock does.
    pub periods_lost: u64,
    /// The latest cycles at which this machine disturbed the loop's timing,
    /// oldest first, at most [`DISTURBANCE_MEMORY`]: for a soak to tell a
    /// stop the machine caused from one it did not.
    pub disturbances: VecDeque<Disturbance>,
}

/// How many [`Disturbance`]s [`SimStats::disturbances`] keeps.
pub const DISTURBANCE_MEMORY: usize = 256;

/// A cycle whose timing this machine, not an injected fault, disturbed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Disturbance {
    /// Controller cycle (0-based, as [`SimStats::cycles`] counts them).
    pub cycle: u64,
    /// Whole send periods lost to an overrun before this cycle (paced).
    pub periods_lost: u32,
    /// The reply to this cycle's intact, delivered datagram missed its
    /// deadline.
    pub reply_missed: bool,
}

/// Round-trip percentiles of on-time replies [µs].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatencySummary {
    /// Number of round trips.
    pub samples: usize,
    /// Median [µs].
    pub p50_us: f64,
    /// 99th percentile [µs].
    pub p99_us: f64,
    /// Largest [µs].
    pub max_us: f64,
}

impl SimStats {
    /// Percentiles of [`SimStats::round_trips_us`] (NaN when empty).
    pub fn latency(&self) -> LatencySummary {
        let mut sorted = self.round_trips_us.clone();
        sorted.sort_unstable();
        let percentile = |p: f64| {
            let index = ((sorted.len() as f64 - 1.0) * p).round() as usize;
            sorted.get(index).map_or(f64::NAN, |v| f64::from(*v))
        };
        LatencySummary {
            samples: sorted.len(),
            p50_us: percentile(0.5),
            p99_us: percentile(0.99),
            max_us: percentile(1.0),
        }
    }
}

/// The simulated controller.
pub struct SimController {
    socket: UdpSocket,
    client: SocketAddr,
    settings: SimSettings,
    plant: Plant,
    frame: GraspFrame,
    joints: JointVector,
    ipo: JointVector,
    state: SessionState,
    cycles_in_state: u32,
    counter: u32,
    cycle: u64,
    random: Gaussian,
    delayed: VecDeque<(u64, Vec<u8>)>,
    held_for_reorder: Option<Vec<u8>>,
    misses: VecDeque<bool>,
    entry_pending: bool,
    last_set_point_pose: Option<Pose>,
    stats: SimStats,
    sent_times: VecDeque<(u32, Instant)>,
    next_tick: Option<Instant>,
    buffer: [u8; MAX_DATAGRAM_BYTES + 1],
}

fn joint_values(values: &JointVector) -> Option<JointValues> {
    Some(JointValues {
        value: values.to_vec(),
    })
}

fn quality_of(misses: usize) -> ConnectionQuality {
    match misses {
        0 => ConnectionQuality::Excellent,
        1..=5 => ConnectionQuality::Good,
        6..=20 => ConnectionQuality::Fair,
        _ => ConnectionQuality::Poor,
    }
}

impl SimController {
    /// Binds to `address`, sends to `client`, runs a plant of `plant`.
    ///
    /// # Errors
    /// [`SimError::Io`] on socket setup, [`SimError::Plant`] on bad
    /// parameters.
    pub fn bind(
        address: SocketAddr,
        client: SocketAddr,
        settings: SimSettings,
        plant: PlantParameters,
    ) -> Result<Self, SimError> {
        let socket = UdpSocket::bind(address)?;
        socket.set_nonblocking(true)?;
        let plant = Plant::new(plant).map_err(SimError::Plant)?;
        let frame = GraspFrame::record(forward(&settings.grasp_joints), settings.heading);
        Ok(Self {
            socket,
            client,
            random: Gaussian::new(settings.faults.seed),
            joints: settings.grasp_joints,
            ipo: settings.grasp_joints,
            settings,
            plant,
            frame,
            state: SessionState::MonitoringWait,
            cycles_in_state: 0,
            counter: 0,
            cycle: 0,
            delayed: VecDeque::new(),
            held_for_reorder: None,
            misses: VecDeque::with_capacity(QUALITY_WINDOW + 1),
            entry_pending: false,
            last_set_point_pose: None,
            stats: SimStats::default(),
            sent_times: VecDeque::with_capacity(SENT_MEMORY),
            next_tick: None,
            buffer: [0; MAX_DATAGRAM_BYTES + 1],
        })
    }

    /// The bound local address.
    ///
    /// # Errors
    /// [`SimError::Io`] from the socket.
    pub fn local_addr(&self) -> Result<SocketAddr, SimError> {
        Ok(self.socket.local_addr()?)
    }

    /// The plant.
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// The session state of the last cycle.
    pub fn state(&self) -> SessionState {
        self.state
    }

    /// Counts so far.
    pub fn stats(&self) -> &SimStats {
        &self.stats
    }

    /// Frame S of the robot model.
    pub fn grasp_frame(&self) -> &GraspFrame {
        &self.frame
    }

    fn enter(&mut self, state: SessionState) {
        if self.state >= SessionState::CommandingWait && state < SessionState::CommandingWait {
            self.stats.overlay_aborts += u64::from(state != SessionState::Idle);
        }
        self.state = state;
        self.cycles_in_state = 0;
    }

    fn quality(&self, faults: &ActiveFaults) -> ConnectionQuality {
        if faults.poor_quality {
            ConnectionQuality::Poor
        } else {
            quality_of(self.misses.iter().filter(|missed| **missed).count())
        }
    }

    /// The state at the start of a cycle: IDLE faults, aborts on quality,
    /// and the monitoring → commanding progression.
    fn update_state(&mut self, faults: &ActiveFaults, quality: ConnectionQuality) {
        if faults.idle {
            if self.state != SessionState::Idle {
                self.enter(SessionState::Idle);
            }
            return;
        }
        match self.state {
            SessionState::Idle => self.enter(SessionState::MonitoringWait),
            SessionState::CommandingWait | SessionState::CommandingActive
                if quality < ConnectionQuality::Good =>
            {
                self.enter(SessionState::MonitoringReady);
            }
            SessionState::MonitoringReady
                if self.cycles_in_state >= self.settings.command_after
                    && quality >= ConnectionQuality::Good =>
            {
                self.ipo = self.held_joints();
                self.enter(SessionState::CommandingWait);
            }
            _ => {}
        }
    }

    /// Joint angles of the set-point the robot holds now.
    fn held_joints(&mut self) -> JointVector {
        let target = self.frame.flange_target(self.plant.set_point().pose);
        match inverse(&target, &self.joints, INVERSE_TOLERANCE, INVERSE_ITERATIONS) {
            Ok(joints) => joints,
            Err(_) => {
                self.stats.inverse_failures += 1;
                self.joints
            }
        }
    }

    fn monitoring_message(
        &self,
        quality: ConnectionQuality,
        torque: &JointVector,
        time: f64,
    ) -> FriMonitoringMessage {
        let joint_overlay = self.settings.overlay == Overlay::JointPosition;
        let commanding = self.state >= SessionState::CommandingWait;
        let (command_mode, control_mode, overlay) = if joint_overlay {
            (
                ClientCommandMode::JointPosition,
                ControlMode::JointImpedance,
                OverlayType::Joint,
            )
        } else {
            (
                ClientCommandMode::Wrench,
                ControlMode::CartesianImpedance,
                OverlayType::Cartesian,
            )
        };
        let whole = time.max(0.0).floor();
        FriMonitoringMessage {
            header: MessageHeader {
                message_identifier: MONITORING_MESSAGE_ID,
                sequence_counter: self.counter,
                reflected_sequence_counter: 0,
            },
            robot_info: Some(RobotInfo {
                number_of_joints: Some(7),
                control_mode: Some(control_mode as i32),
                ..Default::default()
            }),
            monitor_data: Some(MessageMonitorData {
                measured_joint_position: joint_values(&self.joints),
                commanded_joint_position: joint_values(&self.ipo),
                external_torque: joint_values(torque),
                timestamp: Some(TimeStamp {
                    sec: whole as u32,
                    nanosec: ((time.max(0.0) - whole) * 1e9).round().min(999_999_999.0) as u32,
                }),
                ..Default::default()
            }),
            connection_info: Some(ConnectionInfo {
                session_state: self.state as i32,
                quality: quality as i32,
                send_period: Some(self.settings.send_period_ms),
                receive_multiplier: Some(1),
            }),
            ipo_data: Some(MessageIpoData {
                joint_position: (commanding && joint_overlay)
                    .then(|| joint_values(&self.ipo))
                    .flatten(),
                client_command_mode: Some(command_mode as i32),
                overlay_type: commanding.then_some(overlay as i32),
                ..Default::default()
            }),
            ..Default::default()
        }
    }

    /// Records a timing disturbance, forgetting the oldest beyond
    /// [`DISTURBANCE_MEMORY`].
    fn disturbed(&mut self, disturbance: Disturbance) {
        if self.stats.disturbances.len() == DISTURBANCE_MEMORY {
            self.stats.disturbances.pop_front();
        }
        self.stats.disturbances.push_back(disturbance);
    }

    /// Applies the cycle's faults to `datagram`; returns the datagrams to
    /// send now and whether this cycle's datagram is among them intact.
    fn inject(&mut self, faults: &ActiveFaults, mut datagram: Vec<u8>) -> (Vec<Vec<u8>>, bool) {
        let mut out = Vec::new();
        if faults.garbage {
            let length = 1 + (self.random.uniform() * 63.0) as usize;
            out.push(
                (0..length)
                    .map(|_| (self.random.uniform() * 255.0) as u8)
                    .collect(),
            );
            self.stats.garbage_sent += 1;
        }
        let mut intact = true;
        if faults.wrong_crc {
            if let Some(last) = datagram.last_mut() {
                *last ^= 0x5A;
            }
            intact = false;
        }
        let mut delivered_now = false;
        if faults.loss > 0.0 && self.random.uniform() <= faults.loss {
            self.stats.datagrams_dropped += 1;
        } else if faults.delay > 0 {
            self.delayed
                .push_back((self.cycle + u64::from(faults.delay), datagram));
        } else if faults.reorder {
            match self.held_for_reorder.take() {
                Some(held) => {
                    out.push(datagram);
                    out.push(held);
                    delivered_now = true;
                }
                None => self.held_for_reorder = Some(datagram),
            }
        } else {
            if faults.duplicate {
                out.push(datagram.clone());
            }
            out.push(datagram);
            delivered_now = true;
        }
        if !faults.reorder {
            out.extend(self.held_for_reorder.take());
        }
        while self
            .delayed
            .front()
            .is_some_and(|(release, _)| *release <= self.cycle)
        {
            out.extend(self.delayed.pop_front().map(|(_, datagram)| datagram));
        }
        (out, delivered_now && intact)
    }

    /// Waits until `deadline` for the reply to `counter` sent at `sent_at`,
    /// polling the non-blocking socket: a socket receive timeout is rounded
    /// up to the kernel's tick (4 ms at 250 Hz), too coarse for a 1 ms
    /// period and for timing replies. It spins (yielding) for
    /// [`SPIN_FOR`] after sending, where nearly all replies arrive, then
    /// polls every [`POLL_EVERY`] so as not to take a core from the client
    /// (late replies are timed to about that resolution).
    fn await_reply(
        &mut self,
        counter: u32,
        sent_at: Instant,
        deadline: Instant,
    ) -> Result<Option<FriCommandMessage>, SimError> {
        loop {
            let now = Instant::now();
            if now >= deadline {
                return Ok(None);
            }
            let length = match self.socket.recv_from(&mut self.buffer) {
                Ok((length, _)) => length,
                Err(error) if error.kind() == std::io::ErrorKind::WouldBlock => {
                    if now.duration_since(sent_at) < SPIN_FOR {
                        std::thread::yield_now();
                    } else {
                        std::thread::sleep(POLL_EVERY.min(deadline - now));
                    }
                    continue;
                }
                Err(error) => return Err(error.into()),
            };
            let datagram = self.buffer.get(..length).unwrap_or_default();
            let Ok(reply) = decode_command(datagram, self.settings.version) else {
                self.stats.stray_replies += 1;
                continue;
            };
            let reflected = reply.header.reflected_sequence_counter;
            let sent_at = self
                .sent_times
                .iter()
                .rev()
                .find(|(sent, _)| *sent == reflected)
                .map(|(_, at)| *at);
            if let Some(sent_at) = sent_at {
                let round_trip = sent_at.elapsed().as_micros();
                self.stats
                    .round_trips_us
                    .push(u32::try_from(round_trip).unwrap_or(u32::MAX));
            }
            if reflected == counter {
                self.stats.replies_on_time += 1;
                return Ok(Some(reply));
            }
            self.stats.stray_replies += 1;
            self.stats.late_replies += u64::from(sent_at.is_some());
        }
    }

    /// Moves the robot by `reply` (COMMANDING_* states); returns the
    /// set-point to follow, `None` to hold.
    fn apply(&mut self, reply: &FriCommandMessage, measured: Pose) -> Option<SetPoint> {
        let data = reply.command_data.as_ref();
        let joints: Option<JointVector> = data
            .and_then(|data| data.joint_position.as_ref())
            .and_then(|values| values.value.as_slice().try_into().ok());
        let wrench = data
            .and_then(|data| data.cartesian_wrench_feed_forward.as_ref())
            .map(|vector| vector.element.clone());
        let finite = joints.is_none_or(|j| j.iter().all(|v| v.is_finite()))
            && wrench
                .as_ref()
                .is_none_or(|w| w.iter().all(|v| v.is_finite()));
        if !finite {
            self.stats.non_finite_replies += 1;
            return None;
        }
        let reference = if self.settings.overlay == Overlay::JointPosition {
            self.ipo
        } else {
            self.joints
        };
        match self.state {
            SessionState::CommandingWait => {
                let synced = joints.is_some_and(|j| {
                    j.iter()
                        .zip(reference.iter())
                        .all(|(a, b)| (a - b).abs() <= SYNC_TOLERANCE)
                });
                if synced {
                    self.enter(SessionState::CommandingActive);
                    self.stats.commanding_entries += 1;
                    self.entry_pending = true;
                }
                None
            }
            SessionState::CommandingActive => match self.settings.overlay {
                Overlay::JointPosition => {
                    let target = joints?;
                    if std::mem::take(&mut self.entry_pending) {
                        let jump = target
                            .iter()
                            .zip(self.ipo.iter())
                            .map(|(a, b)| (a - b).abs())
                            .fold(0.0, f64::max);
                        self.stats.max_entry_jump = self.stats.max_entry_jump.max(jump);
                    }
                    self.ipo = target;
                    let (pose, _) = self.frame.pose_in_s(&forward(&target));
                    let period = self.settings.period();
                    let velocity = self.last_set_point_pose.map_or(PoseRate::ZERO, |last| {
                        PoseRate::new(
                            (pose.x - last.x) / period,
                            (pose.z - last.z) / period,
                            (pose.psi - last.psi) / period,
                        )
                    });
                    self.last_set_point_pose = Some(pose);
                    Some(SetPoint {
                        pose,
                        velocity,
                        acceleration: PoseRate::ZERO,
                    })
                }
                Overlay::Wrench => {
                    self.entry_pending = false;
                    let w = wrench?;
                    let [fx, fy, fz, a, b, c] = <[f64; 6]>::try_from(w).ok()?;
                    let base = Vector6::new(fx, fy, fz, c, b, a);
                    let s = self.frame.wrench_in_s(&base);
                    let k = self.plant.params().robot.stiffness;
                    Some(SetPoint::hold(Pose::new(
                        measured.x + s.fx / k[0],
                        measured.z + s.fz / k[1],
                        measured.psi + s.ty / k[2],
                    )))
                }
            },
            _ => None,
        }
    }

    /// Runs one cycle.
    ///
    /// # Errors
    /// [`SimError`] on socket or encode failure.
    pub fn run_cycle(&mut self) -> Result<(), SimError> {
        let period = Duration::from_millis(u64::from(self.settings.send_period_ms.clamp(1, 100)));
        let now = Instant::now();
        // Paced: ticks on a fixed grid (no drift), the periods an overrun
        // lost run through by the plant.
        let paced = self.settings.pacing == Pacing::RealTime;
        let cycle_start = match self.next_tick {
            Some(tick) if paced && now < tick + period => tick,
            Some(tick) if paced => {
                // Overrun: the robot's clock does not stop while this
                // process is descheduled. The plant runs on through the
                // whole periods lost, holding its set-point, so the stamps
                // keep wall time (re-anchoring alone made them fall behind
                // the host clock by every lost period, until the client's
                // watchdog called the frames stale).
                let lost = now.duration_since(tick).as_nanos() / period.as_nanos().max(1);
                let lost = u32::try_from(lost).unwrap_or(u32::MAX);
                limb_sim::closed_loop::advance(
                    &mut self.plant,
                    None,
                    self.settings.period() * f64::from(lost),
                );
                self.stats.periods_lost += u64::from(lost);
                self.disturbed(Disturbance {
                    cycle: self.cycle,
                    periods_lost: lost,
                    reply_missed: false,
                });
                // Back on the grid: the cycle that should have started in
                // this period starts now.
                tick + period * lost
            }
            _ => now,
        };
        self.next_tick = Some(cycle_start + period);
        let faults = self.settings.faults.at(self.cycle);
        let quality = self.quality(&faults);
        self.update_state(&faults, quality);
        let quality = self.quality(&faults);
        let measurement = self.plant.measure();
        let flange = self.frame.flange_target(measurement.pose);
        match inverse(&flange, &self.joints, INVERSE_TOLERANCE, INVERSE_ITERATIONS) {
            Ok(joints) => self.joints = joints,
            Err(_) => self.stats.inverse_failures += 1,
        }
        let torque =
            joint_torque_from_wrench(&self.joints, &self.frame.wrench_to_base(measurement.wrench));
        self.counter = self.counter.wrapping_add(faults.counter_jump);
        let counter = self.counter;
        // A robot clock fault: the stamp lags the plant's time.
        let stamp = measurement.time - faults.clock_lag as f64 * self.settings.period();
        let message = self.monitoring_message(quality, &torque, stamp);
        self.counter = self.counter.wrapping_add(1);
        let datagram = encode_monitoring(&message, self.settings.version)?;
        let (datagrams, delivered) = self.inject(&faults, datagram);
        // Taken before sending: the client may answer before send_to returns.
        let sent_at = Instant::now();
        for datagram in &datagrams {
            self.socket.send_to(datagram, self.client)?;
        }
        self.stats.datagrams_sent += datagrams.len() as u64 - u64::from(faults.garbage);
        if self.sent_times.len() == SENT_MEMORY {
            self.sent_times.pop_front();
        }
        self.sent_times.push_back((counter, sent_at));
        let expecting = self.state != SessionState::Idle;
        let deadline = match self.settings.pacing {
            Pacing::RealTime => cycle_start + period,
            Pacing::AsFastAsPossible if expecting && delivered => {
                sent_at + self.settings.reply_timeout
            }
            Pacing::AsFastAsPossible => sent_at + period,
        };
        let reply = if expecting {
            self.await_reply(counter, sent_at, deadline)?
        } else {
            None
        };
        if expecting && reply.is_none() {
            self.stats.missed_cycles += 1;
            self.stats.missed_with_delivery += u64::from(delivered);
            if delivered {
                self.disturbed(Disturbance {
                    cycle: self.cycle,
                    periods_lost: 0,
                    reply_missed: true,
                });
            }
        }
        if expecting {
            self.misses.push_back(reply.is_none());
            if self.misses.len() > QUALITY_WINDOW {
                self.misses.pop_front();
            }
        }
        let set_point = match &reply {
            Some(reply) => self.apply(reply, measurement.pose),
            None => None,
        };
        if self.state == SessionState::MonitoringWait
            && self.cycles_in_state + 1 >= self.settings.ready_after
            && reply.is_some()
        {
            self.enter(SessionState::MonitoringReady);
        } else {
            self.cycles_in_state = self.cycles_in_state.saturating_add(1);
        }
        if self.state != SessionState::CommandingActive {
            self.last_set_point_pose = None;
        }
        limb_sim::closed_loop::advance(&mut self.plant, set_point.as_ref(), self.settings.period());
        if let Some(slot) = self.stats.state_cycles.get_mut(self.state as usize) {
            *slot += 1;
        }
        self.stats.cycles += 1;
        self.cycle += 1;
        let wake = match self.settings.pacing {
            Pacing::RealTime => Some(cycle_start + period),
            Pacing::AsFastAsPossible => (!(expecting && delivered)).then_some(deadline),
        };
        if let Some(wait) = wake.and_then(|wake| wake.checked_duration_since(Instant::now())) {
            std::thread::sleep(wait);
        }
        Ok(())
    }
}
