//! Seeded, deterministic fault schedules for the simulated FRI controller.
//!
//! A schedule is a list of faults, each active over a window of controller
//! cycles (one cycle = one send period). Random choices (which datagram a
//! random loss drops, garbage bytes) come from a generator seeded with the
//! schedule's seed (`limb_sim::noise::Gaussian`'s uniform draws), so a
//! schedule and a seed replay the same faults. Text form, comma-separated:
//! `KIND@START[:CYCLES[:PARAMETER]]`, e.g.
//! `random-loss@2000:3000:0.02,burst-loss@6000:50,counter-jump@7000:1:5000`.
//!
//! | kind | effect on the monitoring datagrams of the window | parameter |
//! |---|---|---|
//! | `random-loss` | each dropped with a probability | probability (0.02) |
//! | `burst-loss` | all dropped | — |
//! | `delay` | each sent a number of cycles late | delay in cycles (3) |
//! | `duplicate` | each sent twice | — |
//! | `reorder` | consecutive pairs sent swapped | — |
//! | `counter-jump` | the sequence counter jumps forward once | jump (5000) |
//! | `poor-quality` | quality reported POOR | — |
//! | `idle` | session drops to IDLE, then re-enters from MONITORING_WAIT | — |
//! | `garbage` | a random non-FRI datagram sent before each | — |
//! | `wrong-crc` | 2.7 CRC corrupted (other versions: last byte flipped) | — |
//! | `clock-back` | the robot's time stamp runs that many cycles behind | cycles (100) |
//! | `clock-stall` | the robot's time stamp stays at the window's start | — |
//! | `clock-repeat` | each time stamp sent on two cycles (the clock at half speed) | — |

use std::fmt;
use std::str::FromStr;

/// One kind of injected fault.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FaultKind {
    /// Drop each datagram with this probability (0..1).
    RandomLoss(f64),
    /// Drop every datagram.
    BurstLoss,
    /// Send each datagram this many cycles late.
    Delay(u32),
    /// Send each datagram twice.
    Duplicate,
    /// Swap consecutive pairs of datagrams.
    Reorder,
    /// Advance the monitor sequence counter by this much, once.
    CounterJump(u32),
    /// Report quality POOR.
    PoorQuality,
    /// Drop the session to IDLE; re-enter afterwards.
    Idle,
    /// Send a random non-FRI datagram before each real one.
    Garbage,
    /// Corrupt the 2.7 CRC (other versions: flip the last byte).
    WrongCrc,
    /// Stamp the messages this many cycles behind the plant's time.
    ClockBack(u32),
    /// Keep stamping the time of the window's first cycle.
    ClockStall,
    /// Stamp each time on two cycles (the robot clock at half speed).
    ClockRepeat,
}

/// A fault active over `cycles` cycles from cycle `start`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScheduledFault {
    /// First cycle of the window.
    pub start: u64,
    /// Length of the window [cycles].
    pub cycles: u64,
    /// The fault.
    pub kind: FaultKind,
}

impl ScheduledFault {
    /// True when the fault acts in `cycle`.
    pub fn active(&self, cycle: u64) -> bool {
        cycle >= self.start && cycle - self.start < self.cycles
    }
}

/// A seeded list of faults.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FaultSchedule {
    /// The faults.
    pub faults: Vec<ScheduledFault>,
    /// Seed of the random choices.
    pub seed: u64,
}

/// The faults acting in one cycle.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ActiveFaults {
    /// Drop probability (1 for a burst).
    pub loss: f64,
    /// Cycles of delay.
    pub delay: u32,
    /// Send twice.
    pub duplicate: bool,
    /// Swap with the next datagram.
    pub reorder: bool,
    /// Counter jump to apply now.
    pub counter_jump: u32,
    /// Quality forced to POOR.
    pub poor_quality: bool,
    /// Session forced to IDLE.
    pub idle: bool,
    /// Garbage datagram before the real one.
    pub garbage: bool,
    /// Corrupt the CRC.
    pub wrong_crc: bool,
    /// How many cycles the time stamp lags the plant's time.
    pub clock_lag: u64,
}

impl FaultSchedule {
    /// A schedule of `faults` with random choices seeded by `seed`.
    pub fn new(faults: Vec<ScheduledFault>, seed: u64) -> Self {
        Self { faults, seed }
    }

    /// What acts in `cycle` (a counter jump only in the window's first
    /// cycle).
    pub fn at(&self, cycle: u64) -> ActiveFaults {
        let mut active = ActiveFaults::default();
        for fault in self.faults.iter().filter(|fault| fault.active(cycle)) {
            match fault.kind {
                FaultKind::RandomLoss(probability) => {
                    active.loss = active.loss.max(probability.clamp(0.0, 1.0));
                }
                FaultKind::BurstLoss => active.loss = 1.0,
                FaultKind::Delay(cycles) => active.delay = active.delay.max(cycles),
                FaultKind::Duplicate => active.duplicate = true,
                FaultKind::Reorder => active.reorder = true,
                FaultKind::CounterJump(jump) if cycle == fault.start => {
                    active.counter_jump = active.counter_jump.wrapping_add(jump);
                }
                FaultKind::CounterJump(_) => {}
                FaultKind::PoorQuality => active.poor_quality = true,
                FaultKind::Idle => active.idle = true,
                FaultKind::Garbage => active.garbage = true,
                FaultKind::WrongCrc => active.wrong_crc = true,
                FaultKind::ClockBack(cycles) => active.clock_lag = u64::from(cycles),
                FaultKind::ClockStall => active.clock_lag = cycle - fault.start,
                FaultKind::ClockRepeat => active.clock_lag = (cycle - fault.start).div_ceil(2),
            }
        }
        active
    }
}

/// A schedule's text could not be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("fault `{text}`: {reason} (form KIND@START[:CYCLES[:PARAMETER]])")]
pub struct FaultParseError {
    text: String,
    reason: &'static str,
}

impl FromStr for ScheduledFault {
    type Err = FaultParseError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let error = |reason| FaultParseError {
            text: text.to_string(),
            reason,
        };
        let (kind, rest) = text
            .split_once('@')
            .ok_or_else(|| error("missing @START"))?;
        let mut parts = rest.split(':');
        let start = parts
            .next()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| error("START is not a cycle number"))?;
        let cycles = match parts.next() {
            Some(s) => s.parse().map_err(|_| error("CYCLES is not a number"))?,
            None => 1,
        };
        let parameter = parts.next();
        let number = |default: f64| -> Result<f64, FaultParseError> {
            parameter.map_or(Ok(default), |p| {
                p.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite() && *v >= 0.0)
                    .ok_or_else(|| error("PARAMETER is not a non-negative number"))
            })
        };
        let kind = match kind {
            "random-loss" => FaultKind::RandomLoss(number(0.02)?.min(1.0)),
            "burst-loss" => FaultKind::BurstLoss,
            "delay" => FaultKind::Delay(number(3.0)?.min(1000.0) as u32),
            "duplicate" => FaultKind::Duplicate,
            "reorder" => FaultKind::Reorder,
            "counter-jump" => {
                FaultKind::CounterJump(number(5000.0)?.min(f64::from(u32::MAX)) as u32)
            }
            "poor-quality" => FaultKind::PoorQuality,
            "idle" => FaultKind::Idle,
            "garbage" => FaultKind::Garbage,
            "wrong-crc" => FaultKind::WrongCrc,
            "clock-back" => FaultKind::ClockBack(number(100.0)?.min(1e9) as u32),
            "clock-stall" => FaultKind::ClockStall,
            "clock-repeat" => FaultKind::ClockRepeat,
            _ => return Err(error("unknown KIND")),
        };
        Ok(Self {
            start,
            cycles,
            kind,
        })
    }
}

impl fmt::Display for ScheduledFault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (name, parameter) = match self.kind {
            FaultKind::RandomLoss(p) => ("random-loss", Some(p)),
            FaultKind::BurstLoss => ("burst-loss", None),
            FaultKind::Delay(d) => ("delay", Some(f64::from(d))),
            FaultKind::Duplicate => ("duplicate", None),
            FaultKind::Reorder => ("reorder", None),
            FaultKind::CounterJump(j) => ("counter-jump", Some(f64::from(j))),
            FaultKind::PoorQuality => ("poor-quality", None),
            FaultKind::Idle => ("idle", None),
            FaultKind::Garbage => ("garbage", None),
            FaultKind::WrongCrc => ("wrong-crc", None),
            FaultKind::ClockBack(c) => ("clock-back", Some(f64::from(c))),
            FaultKind::ClockStall => ("clock-stall", None),
            FaultKind::ClockRepeat => ("clock-repeat", None),
        };
        write!(f, "{name}@{}:{}", self.start, self.cycles)?;
        match parameter {
            Some(p) => write!(f, ":{p}"),
            None => Ok(()),
        }
    }
}

/// Parses a comma-separated schedule (empty text: no faults).
///
/// # Errors
/// The first fault that cannot be read.
pub fn parse_schedule(text: &str, seed: u64) -> Result<FaultSchedule, FaultParseError> {
    let faults = text
        .split(',')
        .map(str::trim)
        .filter(|part| !part.is_empty())
        .map(str::parse)
        .collect::<Result<Vec<_>, _>>()?;
    Ok(FaultSchedule::new(faults, seed))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_round_trips() {
        let text = "random-loss@10:100:0.05,burst-loss@200:50,counter-jump@300:1:5000,idle@400:20";
        let schedule = parse_schedule(text, 7).unwrap();
        let back: Vec<String> = schedule.faults.iter().map(ToString::to_string).collect();
        assert_eq!(back.join(","), text);
        assert!(parse_schedule("bogus@1", 0).is_err());
        assert!(parse_schedule("delay@x", 0).is_err());
    }

    #[test]
    fn counter_jump_acts_once() {
        let schedule = parse_schedule("counter-jump@5:10:9", 0).unwrap();
        assert_eq!(schedule.at(5).counter_jump, 9);
        assert_eq!(schedule.at(6).counter_jump, 0);
    }
}
