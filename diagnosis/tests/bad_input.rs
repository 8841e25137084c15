//! Logs the diagnosis must refuse, with the reason named: too short to
//! hold anything out, no commanded motion to replay, arm lengths that are
//! not lengths, times the sim cannot step to.

use limb_diagnosis::plant::arm::{diagnose, ArmBuild, ArmError, DiagnoseError, Lengths};
use limb_sim::log::Record;

fn log() -> Vec<Record> {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/noisy/case3.csv");
    limb_sim::log::read(&path).unwrap()
}

fn refusal(l1: f64, l2: f64, records: &[Record]) -> DiagnoseError {
    match diagnose(Lengths::Given(l1, l2), ArmBuild::Rod, records, 1, &|_| {}) {
        Err(error) => error,
        Ok(d) => panic!("accepted: {:?}", d.diagnosis.effect),
    }
}

#[test]
fn a_log_too_short_to_hold_out_is_refused() {
    let records: Vec<Record> = log().into_iter().take(300).collect();
    assert!(matches!(
        refusal(0.3, 0.2, &records),
        DiagnoseError::TooShort(_)
    ));
}

#[test]
fn a_log_whose_first_row_has_no_command_is_refused_naming_column_and_time() {
    let mut records = log();
    records[0].command = None;
    match refusal(0.3, 0.2, &records) {
        DiagnoseError::Arm(ArmError::NoCommand { column, time }) => {
            assert_eq!(column, "xd");
            assert_eq!(time, records[0].time);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn bad_arm_lengths_and_times_are_refused() {
    let records = log();
    for (l1, l2) in [
        (f64::NAN, 0.2),
        (0.3, -0.2),
        (f64::INFINITY, 0.2),
        (0.0, 0.2),
    ] {
        assert!(
            matches!(
                refusal(l1, l2, &records),
                DiagnoseError::Arm(ArmError::Arm(_))
            ),
            "{l1} {l2}"
        );
    }
    let mut late = records.clone();
    late[10].time = 1e9;
    assert!(matches!(
        refusal(0.3, 0.2, &late),
        DiagnoseError::Arm(ArmError::Time { sample: 10, .. })
    ));
    assert!(matches!(
        refusal(0.3, 0.2, &[]),
        DiagnoseError::Arm(ArmError::Empty)
    ));
}
