//! `limb diagnose` against `../shared/spec/cli.md`: the JSON contract,
//! the report, the blind self-check and exit code 2 on bad input.

mod common;

use std::process::Command;

const EFFECTS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data/effects");

fn limb(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_limb"))
        .args(args)
        .output()
        .expect("run limb")
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("limb-diagnose-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn json_has_the_contract_keys_and_the_report_is_written() {
    let log = format!("{EFFECTS}/backlash.csv");
    let report = scratch("backlash.html");
    let out = limb(&[
        "diagnose",
        &log,
        "--l1",
        "0.3",
        "--l2",
        "0.2",
        "--json",
        "--report",
        report.to_str().unwrap(),
    ]);
    let json = common::json_of(&out);
    assert_eq!(json["effect"], "backlash");
    let ranking = json["ranking"].as_array().unwrap();
    assert_eq!(ranking.len(), 10);
    assert_eq!(ranking[0]["effect"], "backlash");
    assert!(ranking[0]["score"].as_f64().unwrap() > 0.9);
    assert!((ranking[0]["params"]["width"].as_f64().unwrap() - 0.0261).abs() < 0.001);
    assert_eq!(json["where"]["signals"][0], "psi");
    assert!(json["where"]["t_start"].as_f64().unwrap() < json["where"]["t_end"].as_f64().unwrap());
    let gap = &json["gap"];
    assert_eq!(gap["held_out"], true);
    assert!(gap["metric"].is_string());
    let (before, after) = (
        gap["before"].as_f64().unwrap(),
        gap["after"].as_f64().unwrap(),
    );
    assert!((gap["shrink"].as_f64().unwrap() - (1.0 - after / before)).abs() < 1e-12);
    let page = std::fs::read_to_string(&report).unwrap();
    assert!(
        page.starts_with("<!DOCTYPE html>") && page.contains("<svg") && page.contains("backlash")
    );
    assert!(
        !page.contains("src=\"http") && !page.contains("<script"),
        "self-contained"
    );
    assert_eq!(page.matches("<svg").count(), page.matches("</svg>").count());
}

#[test]
fn the_human_output_names_effect_gap_and_where() {
    let log = format!("{EFFECTS}/none.csv");
    let out = limb(&["diagnose", &log, "--l1", "0.3", "--l2", "0.2"]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.starts_with("effect   none\n"), "{text}");
    assert!(text.contains("nowhere beyond the noise"), "{text}");
}

#[test]
fn bad_input_exits_2_with_one_line() {
    let short = scratch("short.csv");
    let text = std::fs::read_to_string(format!("{EFFECTS}/none.csv")).unwrap();
    std::fs::write(
        &short,
        text.lines().take(200).collect::<Vec<_>>().join("\n"),
    )
    .unwrap();
    let nan = scratch("nan.csv");
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[40] = lines[40]
        .replacen("0.", "NaN,", 1)
        .replacen(",NaN,", ",NaN", 1);
    std::fs::write(&nan, lines.join("\n")).unwrap();
    let log = format!("{EFFECTS}/none.csv");
    for (args, says) in [
        (
            vec![
                "diagnose",
                short.to_str().unwrap(),
                "--l1",
                "0.3",
                "--l2",
                "0.2",
            ],
            "too short",
        ),
        (
            vec![
                "diagnose",
                nan.to_str().unwrap(),
                "--l1",
                "0.3",
                "--l2",
                "0.2",
            ],
            ":41:",
        ),
        (
            vec!["diagnose", &log, "--l1", "nan", "--l2", "0.2"],
            "arm lengths",
        ),
        (vec!["diagnose", &log, "--l1", "0.3"], "required"),
        (
            vec!["diagnose", "/no/such.csv", "--l1", "0.3", "--l2", "0.2"],
            "/no/such.csv",
        ),
    ] {
        let out = limb(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
        assert!(out.stdout.is_empty());
    }
}

#[test]
fn a_log_of_another_motion_exits_2() {
    let text = std::fs::read_to_string(format!("{EFFECTS}/none.csv")).unwrap();
    let moved: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(i, line)| {
            if i < 500 {
                return line.to_string();
            }
            // Raise the commanded height zd (third column) by 5 cm.
            let mut fields: Vec<String> = line.split(',').map(String::from).collect();
            let zd: f64 = fields[2].parse().unwrap();
            fields[2] = format!("{:.6}", zd + 0.05);
            fields.join(",")
        })
        .collect();
    let path = scratch("moved.csv");
    std::fs::write(&path, moved.join("\n")).unwrap();
    let out = limb(&[
        "diagnose",
        path.to_str().unwrap(),
        "--l1",
        "0.3",
        "--l2",
        "0.2",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("commanded motion"));
}

#[test]
fn the_blind_self_check_is_seeded_and_reports_its_figures() {
    let run = || limb(&["diagnose", "--self-check", "3", "--seed", "5", "--json"]);
    let out = run();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["logs"], 3);
    assert_eq!(json["classes"].as_array().unwrap().len(), 11);
    let total: u64 = json["confusion"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|row| row.as_array().unwrap().iter().map(|c| c.as_u64().unwrap()))
        .sum();
    assert_eq!(total, 3);
    assert_eq!(json["top1_accuracy"], 1.0, "{}", json["cases"]);
    assert_eq!(json["none_for_large_effects"], 0);
    let cases = &json["cases"];
    assert_eq!(cases.as_array().unwrap().len(), 3);
    let again: serde_json::Value = serde_json::from_slice(&run().stdout).unwrap();
    assert_eq!(&again["cases"], cases, "same seed, same logs and answers");
}

/// The report renders in a real browser: headless Chromium (Debian
/// package `chromium`, installed by `.ci/run` when it can be) parses it
/// into a DOM with one chart per located signal and takes a screenshot.
/// Without Chromium the test says so and checks nothing more.
#[test]
fn the_report_renders_in_headless_chromium() {
    let Ok(chromium) = which("chromium") else {
        eprintln!(
            "chromium is not installed: report rendering not checked (apt-get install chromium)"
        );
        return;
    };
    let report = scratch("slip.html");
    let log = format!("{EFFECTS}/grasp_slip.csv");
    let out = limb(&[
        "diagnose",
        &log,
        "--l1",
        "0.3",
        "--l2",
        "0.18",
        "--report",
        report.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0));
    let url = format!("file://{}", report.display());
    let browser = |extra: &[&str]| {
        Command::new(&chromium)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--hide-scrollbars",
            ])
            .args(extra)
            .arg(&url)
            .output()
            .expect("run chromium")
    };
    let dom = String::from_utf8_lossy(&browser(&["--dump-dom"]).stdout).into_owned();
    // Six located signals: a trace chart and a residual chart each.
    assert_eq!(
        dom.matches("<svg").count(),
        12,
        "{}",
        &dom[..dom.len().min(400)]
    );
    assert!(dom.matches("<polyline").count() >= 30);
    let png = scratch("slip.png");
    let shot = browser(&[
        "--window-size=1000,1400",
        &format!("--screenshot={}", png.display()),
    ]);
    assert!(
        shot.status.success(),
        "{}",
        String::from_utf8_lossy(&shot.stderr)
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    assert!(
        bytes.len() > 20_000,
        "a blank page is small: {} bytes",
        bytes.len()
    );
}

fn which(program: &str) -> Result<std::path::PathBuf, ()> {
    std::env::var_os("PATH")
        .iter()
        .flat_map(std::env::split_paths)
        .map(|dir| dir.join(program))
        .find(|path| path.is_file())
        .ok_or(())
}
