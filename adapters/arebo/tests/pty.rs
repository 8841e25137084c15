//! End-to-end tests over a real pseudo-terminal: the simulated AREBO
//! device thread and the host [`Session`] speak the serial protocol.

use limb_arebo::calibration::{self, CalibrationLimits};
use limb_arebo::encoder::BacklashCompensator;
use limb_arebo::link::{self, DeviceFault, FaultSwitch, Session, SessionState, StopCause};
use limb_arebo::protocol::Telemetry;
use limb_arebo::safety::{AreboLimit, SafetyLimits};
use limb_arebo::sim::{self, Setup, CALIBRATION_PHASE};
use limb_kernel::monitor::Limit;
use std::time::{Duration, Instant};

const FRAMES_PER_PHASE: usize = (CALIBRATION_PHASE / sim::SAMPLE_PERIOD) as usize;

/// Runs calibration (2 × 15 s) and 30 s of the accuracy polysine through
/// the pty faster than real time (0.3 ms per 5 ms frame); returns (ψx error [deg], origin error [mm],
/// length error [mm], median flexion and abduction errors [deg]).
fn calibrate_over_pty(setup: Setup) -> (f64, f64, f64, f64, f64) {
    let pty = link::pseudo_terminal().unwrap();
    let small = sim::sphere_calibration(1);
    let motion = sim::accuracy_motion(2);
    let trajectory = Box::new(move |t: f64| {
        if t < CALIBRATION_PHASE {
            sim::flexion_calibration(t)
        } else if t < 2.0 * CALIBRATION_PHASE {
            small.at(t - CALIBRATION_PHASE)
        } else {
            motion.at(t - 2.0 * CALIBRATION_PHASE)
        }
    });
    let total = 4 * FRAMES_PER_PHASE;
    let device = link::spawn_device(
        pty.device.try_clone().unwrap(),
        setup,
        trajectory,
        total,
        Duration::from_micros(300),
        FaultSwitch::default(),
    )
    .unwrap();
    let mut session = Session::open(&pty.path, SafetyLimits::default()).unwrap();
    let mut frames: Vec<Telemetry> = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(120);
    while frames.len() < total && Instant::now() < deadline {
        frames.extend(session.poll());
    }
    let record = device.join().unwrap();
    assert_eq!(frames.len(), record.frames, "every streamed frame decoded");
    let mut compensator = BacklashCompensator::new(setup.compensated_backlash);
    let estimates: Vec<_> = frames
        .iter()
        .map(|f| {
            (
                sim::endpoint_estimate(&mut compensator, &f.counts),
                compensator.settled(),
            )
        })
        .collect();
    // Calibration keeps the samples outside the joints' play.
    let settled = |range: std::ops::Range<usize>| -> Vec<_> {
        estimates[range]
            .iter()
            .filter(|(_, s)| *s)
            .map(|(p, _)| *p)
            .collect()
    };
    let plane = calibration::fit_plane(&settled(0..FRAMES_PER_PHASE)).unwrap();
    let sphere = calibration::fit_sphere(&settled(FRAMES_PER_PHASE..2 * FRAMES_PER_PHASE)).unwrap();
    let model = calibration::validate(&plane, &sphere, &CalibrationLimits::default()).unwrap();
    let mut flexion = Vec::new();
    let mut abduction = Vec::new();
    for ((p, _), truth) in estimates
        .iter()
        .zip(record.truth.iter())
        .skip(2 * FRAMES_PER_PHASE)
    {
        let estimate = model.angles(p).unwrap();
        flexion.push((estimate.flexion - truth.flexion).abs().to_degrees());
        abduction.push((estimate.abduction - truth.abduction).abs().to_degrees());
    }
    flexion.sort_by(f64::total_cmp);
    abduction.sort_by(f64::total_cmp);
    (
        (model.psi_x() - setup.psi_x).to_degrees(),
        (model.origin() - setup.origin).norm() * 1e3,
        (model.length() - setup.length) * 1e3,
        flexion[flexion.len() / 2],
        abduction[abduction.len() / 2],
    )
}

/// Over the pty, with encoder quantisation, without and with the 1°
/// backlash dead-band (compensated by the adapter), calibration recovers
/// ψx within 1°, origin and l within 5 mm, and the median joint-angle
/// errors stay under 1° (paper: 2.10° / 1.30°).
#[test]
fn calibration_and_tracking_over_the_pty() {
    let clean = calibrate_over_pty(Setup {
        backlash: [0.0; 3],
        compensated_backlash: [0.0; 3],
        ..Setup::default()
    });
    println!("no backlash: {clean:?}");
    assert!(clean.0.abs() < 1.0 && clean.1 < 5.0 && clean.2.abs() < 5.0);
    assert!(clean.3 < 1.0 && clean.4 < 1.0);
    let backlash = calibrate_over_pty(Setup::default());
    println!("1 deg backlash on theta1..theta3: {backlash:?} (paper: 2.10 / 1.30 deg)");
    assert!(backlash.0.abs() < 1.0 && backlash.1 < 5.0 && backlash.2.abs() < 5.0);
    assert!(backlash.3 < 1.0 && backlash.4 < 1.0);
}

fn poll_for(session: &mut Session, seconds: f64) -> usize {
    let end = Instant::now() + Duration::from_secs_f64(seconds);
    let mut frames = 0;
    while Instant::now() < end {
        frames += session.poll().len();
    }
    frames
}

/// Garbage, truncated frames and wrong checksums are skipped without a
/// stop; a stalled device trips the stale-data safe stop; an unplugged one
/// too; nothing panics.
#[test]
fn faults_over_the_pty() {
    for final_fault in [DeviceFault::Stall, DeviceFault::Unplug] {
        let pty = link::pseudo_terminal().unwrap();
        let faults = FaultSwitch::default();
        let motion = sim::accuracy_motion(3);
        let device = link::spawn_device(
            pty.device.try_clone().unwrap(),
            Setup::default(),
            Box::new(move |t| motion.at(t)),
            4000,
            Duration::from_millis(1),
            faults.clone(),
        )
        .unwrap();
        let mut session = Session::open(&pty.path, SafetyLimits::default()).unwrap();
        assert!(poll_for(&mut session, 0.3) > 50);
        faults.set(DeviceFault::Garbage);
        let during_garbage = poll_for(&mut session, 0.3);
        assert!(
            during_garbage > 50,
            "frames resynchronise: {during_garbage}"
        );
        assert!(session.stats().checksum_errors > 10);
        assert_eq!(session.state(), SessionState::Running);
        faults.set(final_fault);
        poll_for(&mut session, 0.3);
        match session.state() {
            SessionState::SafeStop(StopCause::Violation(v)) => {
                assert_eq!(v.limit, AreboLimit::Kernel(Limit::StaleSensor))
            }
            SessionState::SafeStop(StopCause::PortLost) => {
                assert_eq!(final_fault, DeviceFault::Unplug)
            }
            SessionState::Running => panic!("{final_fault:?} did not stop the session"),
        }
        faults.set(DeviceFault::Unplug);
        drop(session);
        device.join().unwrap();
    }
}

/// Without heartbeats the device flags the missing heartbeat (error bit 0)
/// after about 1 s (it then also stops applying the torque target; that
/// part is not asserted here).
#[test]
fn device_flags_a_missing_heartbeat() {
    use limb_arebo::protocol::{Command, ControlType, Decoder, ERROR_HEARTBEAT, TELEMETRY_HEADER};
    use std::io::{Read, Write};
    let pty = link::pseudo_terminal().unwrap();
    let motion = sim::accuracy_motion(4);
    let device = link::spawn_device(
        pty.device.try_clone().unwrap(),
        Setup::default(),
        Box::new(move |t| motion.at(t)),
        400,
        Duration::from_millis(5),
        FaultSwitch::default(),
    )
    .unwrap();
    // A bare host: starts the stream, asks for torque control, never beats.
    let mut port = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&pty.path)
        .unwrap();
    port.write_all(&Command::Heartbeat.encode()).unwrap();
    port.write_all(&Command::SetControlType(ControlType::Torque).encode())
        .unwrap();
    port.write_all(&Command::StartStream.encode()).unwrap();
    let mut decoder = Decoder::new(TELEMETRY_HEADER);
    let mut frames: Vec<(Instant, Telemetry)> = Vec::new();
    let start = Instant::now();
    let mut bytes = [0u8; 512];
    while start.elapsed() < Duration::from_millis(1600) {
        let n = port.read(&mut bytes).unwrap_or(0);
        for b in bytes.iter().take(n) {
            if let Some(t) = decoder.push(*b).and_then(|p| Telemetry::parse(&p)) {
                frames.push((Instant::now(), t));
            }
        }
    }
    let early: Vec<_> = frames
        .iter()
        .filter(|(t, _)| t.duration_since(start) < Duration::from_millis(700))
        .collect();
    let late: Vec<_> = frames
        .iter()
        .filter(|(t, _)| t.duration_since(start) > Duration::from_millis(1300))
        .collect();
    assert!(!early.is_empty() && !late.is_empty());
    assert!(early.iter().all(|(_, f)| f.error & ERROR_HEARTBEAT == 0));
    assert!(late.iter().all(|(_, f)| f.error & ERROR_HEARTBEAT != 0));
    drop(port);
    device.join().unwrap();
}
