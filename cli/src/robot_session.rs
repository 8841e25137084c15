//! The session of a real robot's command (`limb kuka run`, `limb arebo run
//! --kernel`): its options and [`run_robot`], the session under the
//! scripted operator or a Zenoh supervisor, logged as `--log` says.

use crate::error::CliError;
use crate::session_log::{EventRecord, LogFile};
use crate::zenoh::NodeLink;
use limb_kernel::{Kernel, KernelConfig};
use limb_session::log::Logged;
use limb_session::{ArrivalClock, Operator, Outcome, Robot, SessionPlan};
use std::path::PathBuf;

/// The session options of a real robot's command (`limb kuka run`, `limb
/// arebo run --kernel`).
#[derive(clap::Args)]
pub struct SessionArgs {
    /// The session's clock: host (the host's monotonic clock, for a real
    /// robot: a robot clock that stalls or lags, or a backlog read late,
    /// ages its frames) or robot (its stamps, for a simulated robot whose
    /// clock is the simulation's: an unpaced or lock-stepped one).
    #[arg(long, default_value = "host")]
    clock: String,
    /// End the session when the kernel completes a manipulation or stops
    /// (otherwise it runs for --seconds, answering with hold).
    #[arg(long)]
    until_stopped: bool,
    /// Supervise the session over Zenoh (`--robot`, `--listen` or
    /// `--connect`, `--key-file`: as `limb zenoh node`) instead of the
    /// scripted operator.
    #[arg(long)]
    zenoh: bool,
    #[command(flatten)]
    link: NodeLink,
    /// Write the session log (every frame stepped on: robot stamp,
    /// commanded set-point, measured pose and wrench in frame S) to this
    /// CSV in the plant.md format, and every kernel step (silences
    /// included) to FILE.steps.csv beside it.
    #[arg(long)]
    log: Option<PathBuf>,
}

impl SessionArgs {
    /// `--clock`.
    ///
    /// # Errors
    /// [`CliError::BadInput`] for another word than host or robot.
    pub fn clock(&self) -> Result<ArrivalClock, CliError> {
        match self.clock.as_str() {
            "host" => Ok(ArrivalClock::Host),
            "robot" => Ok(ArrivalClock::Robot),
            other => Err(CliError::BadInput(format!(
                "--clock {other}: expected host or robot"
            ))),
        }
    }

    /// True when an option is given that only a kernel session uses.
    pub fn any(&self) -> bool {
        self.zenoh || self.until_stopped || self.log.is_some()
    }
}

/// How a robot's session ended: the kernel, the outcome (or the robot's
/// own failure) and the events.
pub struct RobotSession<E> {
    /// The kernel at the end.
    pub kernel: Box<Kernel>,
    /// The outcome, or the robot's failure that ended the session.
    pub outcome: Result<Outcome, E>,
    /// The kernel's events.
    pub events: EventRecord,
}

/// Runs one session of the default kernel on `robot` as `args` say:
/// supervised over Zenoh, or by the scripted operator with `plan` (which
/// ends the session when it completes or stops with `--until-stopped`,
/// else leaves the end to the robot); the log written to `--log`. The log
/// is finished whatever ended the session.
///
/// # Errors
/// [`CliError`] for a bad kernel configuration, link setting or log file.
pub fn run_robot<R: Robot + Logged>(
    robot: &mut R,
    args: &SessionArgs,
    plan: SessionPlan,
) -> Result<RobotSession<R::Error>, CliError> {
    let log = args.log.as_deref();
    let link = args.zenoh.then_some(&args.link);
    let mut kernel = Box::new(
        Kernel::new(KernelConfig::default())
            .map_err(|e| CliError::BadInput(format!("kernel configuration: {e}")))?,
    );
    let mut observers = (EventRecord::default(), LogFile::create(log)?);
    let outcome = match link {
        Some(link) => {
            let (link, mut supervision) = link.open(*kernel.config())?;
            let outcome = limb_session::run(&mut kernel, robot, &mut supervision, &mut observers);
            link.close()
                .map_err(|error| CliError::Internal(error.to_string()))?;
            outcome
        }
        None => {
            let mut operator = if args.until_stopped {
                Operator::new(plan)
            } else {
                Operator::continuing(plan)
            };
            limb_session::run(&mut kernel, robot, &mut operator, &mut observers)
        }
    };
    let (events, written) = observers;
    LogFile::finish(written, log)?;
    Ok(RobotSession {
        kernel,
        outcome,
        events,
    })
}
