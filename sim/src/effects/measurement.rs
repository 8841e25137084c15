//! The measurement chain without the plant: the measurement-side effects
//! applied to a noise-free record of what the robot senses, in the
//! plant's own order (compliance and tilt, delay, backlash, rounding), so
//! that a diagnosis predicts them in microseconds instead of re-running
//! the plant. Quantization is predicted as the *expected* rounded reading
//! over the measurement noise ([`super::Quantization::expected`]), since
//! the real sensor rounds its noisy reading.
//!
//! [`measured`] needs the `std` feature: the tilt uses the host's
//! `sin_cos` (and the expected rounding its `round`), as the diagnosis
//! always has, so that its answers stay the same to the last bit.

use crate::sensing::Measurement;

/// Effects that only change what is measured: those [`measured`] applies.
pub const MEASUREMENT_SIDE: [&str; 5] = [
    "backlash",
    "quantization",
    "latency",
    "grasp_compliance",
    "plane_tilt",
];

/// The sensed channels of one instant: x, z, psi, y, fx, fz, ty.
pub type Reading = [f64; 7];

/// The channels of a measurement.
pub fn reading(m: &Measurement) -> Reading {
    [
        m.pose.x,
        m.pose.z,
        m.pose.psi,
        m.lateral,
        m.wrench.fx,
        m.wrench.fz,
        m.wrench.ty,
    ]
}

/// The readings at integration steps `steps` (increasing) of `record`,
/// the noise-free readings of every 0.5 ms step, with the
/// measurement-side `effects` applied (the others are ignored). A step
/// the delay reaches back before the start reads the first; one beyond
/// the record reads NaN.
#[cfg(feature = "std")]
pub fn measured<'a>(
    record: &'a [Reading],
    steps: &'a [usize],
    effects: &super::Effects,
) -> impl Iterator<Item = Reading> + 'a {
    let effects = *effects;
    let delay = effects.latency.map_or(0, |l| l.steps());
    let mut follower = 0.0;
    steps.iter().map(move |&step| {
        let mut s = record
            .get(step.saturating_sub(delay))
            .copied()
            .unwrap_or([f64::NAN; 7]);
        let mut pose = [s[0], s[1], s[2]];
        if let Some(compliance) = effects.grasp_compliance {
            pose = compliance.end_effector(pose, [s[4], s[5], s[6]]);
        }
        if let Some(tilt) = effects.plane_tilt {
            let (sin, cos) = tilt.angle.sin_cos();
            s[3] = pose[1] * sin;
            pose[1] *= cos;
        }
        if let Some(backlash) = effects.backlash {
            follower = backlash.follow(follower, pose[2]);
            pose[2] = follower;
        }
        if let Some(q) = effects.quantization {
            pose = q.expected(pose);
        }
        [pose[0], pose[1], pose[2], s[3], s[4], s[5], s[6]]
    })
}

#[cfg(test)]
mod tests {
    use super::measured;
    use crate::effects::{Effect, Effects};

    #[test]
    fn no_effect_reads_the_record_and_latency_reads_it_late() {
        let record: Vec<[f64; 7]> = (0..10).map(|k| [k as f64; 7]).collect();
        let steps = [0, 3, 9, 12];
        let none: Vec<_> = measured(&record, &steps, &Effects::default()).collect();
        assert_eq!(&none[..3], &[record[0], record[3], record[9]]);
        assert!(none[3].iter().all(|v| v.is_nan()));
        let late = Effects::new(&[Effect::parse("latency", &["delay=0.002"]).unwrap()]).unwrap();
        let late: Vec<_> = measured(&record, &steps, &late).collect();
        assert_eq!(&late[..3], &[record[0], record[0], record[5]]);
        assert_eq!(late[3], record[8]);
    }
}
