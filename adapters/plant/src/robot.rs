//! A `limb-plant/1` plant as the robot of a `limb-session` session.
//!
//! # Theory of operation
//! [`PlantRobot::connect`] opens the stream and takes the plant's
//! handshake (answering it, or refusing it and closing). Each
//! [`Robot::sense`] then reads one frame, checks it strictly (fields,
//! finiteness, the handshake's truth names, `t` strictly increasing) and
//! hands the kernel its sample; each [`Robot::actuate`] answers with the
//! step's command. Frames arrive on the plant's clock (`arrival = t`): the
//! plant's time is the session's, as fast or slow as it runs.
//!
//! A fault of the plant (any [`Fault`]) is kept with its line and ends the
//! session as [`Sensed::Ended`]: the loop stops without stepping the
//! kernel on the refused line, the runner reads [`PlantRobot::failure`],
//! stops the kernel and reports a robot failure; the session logs hold
//! every frame up to the last good one. A plant's own `{"end": …}` ends
//! the session too, not as a failure ([`PlantRobot::plant_end`]).
//! [`PlantRobot::finish`] sends limb's `end` and closes the link.

use crate::error::{Fault, PlantError};
use crate::transport::{Endpoint, Link};
use crate::wire::{self, Handshake, Message, PlantFrame};
use core::convert::Infallible;
use limb_kernel::Command;
use limb_session::log::Logged;
use limb_session::{Frame, Robot, Sensed};
use std::collections::BTreeSet;
use std::time::Duration;

/// plant.md's truth columns: the session log writes them first (empty
/// when the plant does not give one), so `limb estimate` and `limb
/// diagnose` read a plant's log as a reference-plant log.
pub const PLANT_MD_TRUTH: [&str; 6] =
    ["q1", "q2", "elbow_x", "elbow_z", "shoulder_x", "shoulder_z"];

/// An external plant driven in lockstep.
pub struct PlantRobot {
    link: Option<Link>,
    handshake: Handshake,
    /// Lines the plant sent so far (1 = the handshake).
    line: u64,
    /// The session's budget on the plant's clock, from its first frame [s].
    until: f64,
    first: Option<PlantFrame>,
    last: Option<PlantFrame>,
    frames: u64,
    failure: Option<PlantError>,
    plant_end: Option<String>,
    unknown: BTreeSet<String>,
    /// Index in the truth of each column after plant.md's (then `fy`).
    columns: Vec<String>,
    out: String,
}

/// How a plant's session ended, once its link is closed.
#[derive(Debug, Clone, PartialEq)]
pub struct Ending {
    /// The robot failure that ended it, if one did.
    pub failure: Option<PlantError>,
    /// The reason the plant gave when it ended the session itself.
    pub plant_end: Option<String>,
    /// Frames the plant sent and the kernel stepped on.
    pub frames: u64,
    /// Keys the plant sent that this version does not know (ignored).
    pub unknown_keys: Vec<String>,
}

impl PlantRobot {
    /// Starts or reaches the plant at `endpoint` and takes its handshake;
    /// `timeout` bounds every wait for the plant, `until` is the session's
    /// length on the plant's clock [s].
    ///
    /// # Errors
    /// The plant cannot be reached, or its handshake is refused (limb
    /// answers `{"error": …}` and closes the link).
    pub fn connect(endpoint: &Endpoint, timeout: Duration, until: f64) -> Result<Self, PlantError> {
        let at = |line, fault| PlantError { line, fault };
        let mut link = Link::open(endpoint, timeout).map_err(|f| at(0, f))?;
        let decoded = link
            .read_line()
            .and_then(|line| wire::decode_handshake(&line));
        let decoded = match decoded {
            Ok(decoded) => decoded,
            Err(fault) => {
                let _ = link.write_line(&wire::refuse_or_end("error", &fault.to_string()));
                let _ = link.close(matches!(fault, Fault::Timeout(_)));
                return Err(at(1, fault));
            }
        };
        link.write_line(&wire::accept()).map_err(|f| at(1, f))?;
        let handshake = decoded.message;
        let columns = PLANT_MD_TRUTH
            .iter()
            .map(|s| (*s).to_string())
            .chain(["fy".to_string()])
            .chain(
                handshake
                    .truth
                    .iter()
                    .filter(|name| !PLANT_MD_TRUTH.contains(&name.as_str()))
                    .cloned(),
            )
            .collect();
        Ok(Self {
            link: Some(link),
            handshake,
            line: 1,
            until,
            first: None,
            last: None,
            frames: 0,
            failure: None,
            plant_end: None,
            unknown: decoded.unknown.into_iter().collect(),
            columns,
            out: String::new(),
        })
    }

    /// The plant's handshake.
    pub fn handshake(&self) -> &Handshake {
        &self.handshake
    }

    /// The first frame the kernel stepped on.
    pub fn first_frame(&self) -> Option<&PlantFrame> {
        self.first.as_ref()
    }

    /// The last frame the kernel stepped on.
    pub fn last_frame(&self) -> Option<&PlantFrame> {
        self.last.as_ref()
    }

    /// The truth value `name` of `frame`, when the plant gives it.
    pub fn truth_of(&self, frame: &PlantFrame, name: &str) -> Option<f64> {
        let index = self.handshake.truth.iter().position(|n| n == name)?;
        frame.truth.get(index).copied()
    }

    /// The fault that ended the session, if one did.
    pub fn failure(&self) -> Option<&PlantError> {
        self.failure.as_ref()
    }

    /// The reason the plant gave when it ended the session itself.
    pub fn plant_end(&self) -> Option<&str> {
        self.plant_end.as_deref()
    }

    /// Sends `{"end": reason}` (unless the plant ended or failed first),
    /// closes the link and says how the session ended. A plant whose
    /// program exits with a failure status is a failure too.
    pub fn finish(mut self, reason: &str) -> Ending {
        if let Some(mut link) = self.link.take() {
            let hung = matches!(
                self.failure,
                Some(PlantError {
                    fault: Fault::Timeout(_),
                    ..
                })
            );
            if self.plant_end.is_none() {
                let why = self
                    .failure
                    .as_ref()
                    .map_or_else(|| reason.to_string(), ToString::to_string);
                let _ = link.write_line(&wire::refuse_or_end("end", &why));
            }
            if let Some(status) = link.close(hung) {
                if self.failure.is_none() {
                    self.failure = Some(PlantError {
                        line: self.line,
                        fault: Fault::ExitStatus(status),
                    });
                }
            }
        }
        Ending {
            failure: self.failure,
            plant_end: self.plant_end,
            frames: self.frames,
            unknown_keys: self.unknown.into_iter().collect(),
        }
    }

    fn fail(&mut self, fault: Fault) -> Sensed {
        self.failure = Some(PlantError {
            line: self.line,
            fault,
        });
        Sensed::Ended
    }

    /// Reads and checks the next frame.
    fn next(&mut self) -> Sensed {
        let Some(link) = self.link.as_mut() else {
            return Sensed::Ended;
        };
        if self.failure.is_some() || self.plant_end.is_some() {
            return Sensed::Ended;
        }
        let line = match link.read_line() {
            Ok(line) => line,
            Err(fault) => {
                // A line that never arrived has the next number.
                self.line += 1;
                return self.fail(fault);
            }
        };
        self.line += 1;
        let decoded = match wire::decode_message(&line, &self.handshake.truth) {
            Ok(decoded) => decoded,
            Err(fault) => return self.fail(fault),
        };
        self.unknown.extend(decoded.unknown);
        let frame = match decoded.message {
            Message::End(reason) => {
                self.plant_end = Some(reason);
                return Sensed::Ended;
            }
            Message::Frame(frame) => frame,
        };
        let t = frame.sample.time;
        if let Some(previous) = self.last.as_ref().map(|f| f.sample.time) {
            if t <= previous {
                return self.fail(Fault::TimeNotIncreasing { t, previous });
            }
        }
        let start = self.first.as_ref().map_or(t, |f| f.sample.time);
        if t - start >= self.until {
            return Sensed::Ended;
        }
        if self.first.is_none() {
            self.first = Some(frame.clone());
        }
        self.frames += 1;
        let sensed = Sensed::Frame(Frame {
            sample: frame.sample,
            lateral: frame.y,
            arrival: t,
            following: true,
        });
        self.last = Some(frame);
        sensed
    }
}

impl Robot for PlantRobot {
    type Error = Infallible;

    fn sense(&mut self) -> Result<Sensed, Infallible> {
        Ok(self.next())
    }

    fn actuate(&mut self, command: &Command) -> Result<(), Infallible> {
        let Some(link) = self.link.as_mut() else {
            return Ok(());
        };
        self.out.clear();
        let sent =
            wire::encode_command(command, &mut self.out).and_then(|()| link.write_line(&self.out));
        if let Err(fault) = sent {
            self.fail(fault);
        }
        Ok(())
    }
}

impl Logged for PlantRobot {
    fn columns(&self) -> Vec<&str> {
        self.columns.iter().map(String::as_str).collect()
    }

    fn values(&self, out: &mut Vec<Option<f64>>) {
        let Some(frame) = self.last.as_ref() else {
            return;
        };
        out.extend(PLANT_MD_TRUTH.iter().map(|name| self.truth_of(frame, name)));
        out.push(frame.fy);
        out.extend(
            self.columns[PLANT_MD_TRUTH.len() + 1..]
                .iter()
                .map(|name| self.truth_of(frame, name)),
        );
    }
}
