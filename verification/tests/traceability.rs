//! Traceability between `spec/requirements.toml`, `spec/hazards.md` and the
//! checks in the repository. Fails when:
//! * a requirement names no check, or a check that does not exist;
//! * a cited check (of any engine) does not mention the citing
//!   requirement's ID in its doc comment;
//! * a `kani:` entry is not a Kani harness (`kani::proof`) named
//!   `verify_req_…`, a `proptest:` entry is not in a file with properties;
//! * a `req_*` test or `verify_req_*` harness (tests and the kernel's
//!   sources) is named by no requirement, or mentions an ID that does not
//!   exist;
//! * the record of real Kani's runs (`[[kani.run]]`) names a harness that
//!   is not cited, misses a cited harness, names one twice or gives a
//!   result other than `verified`, `timeout` or `failed`;
//! * a requirement cites an unknown hazard, or a hazard has no requirement;
//! * `spec/traceability.md` is not the table this test generates (run with
//!   `LIMB_BLESS=1` to rewrite it).

use serde::Deserialize;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
struct Spec {
    kani: KaniRecord,
    requirement: Vec<Requirement>,
}

/// What real Kani has said about the harnesses: one run per cited harness.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KaniRecord {
    version: String,
    cbmc: String,
    date: String,
    machine: String,
    run: Vec<KaniRun>,
}

/// One harness's latest run under real Kani (`verification/kani-run.sh`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KaniRun {
    harness: String,
    /// `verified` (every check and every cover), `timeout` or `failed`.
    result: String,
    /// Wall time [s].
    seconds: u32,
    /// Peak resident memory [MiB].
    mib: u32,
    /// Covers satisfied / covers.
    covers: String,
    /// CBMC options the run took beside Kani's (`kani-run.sh`'s table).
    #[serde(default)]
    cbmc_args: Option<String>,
}

#[derive(Deserialize)]
struct Requirement {
    id: String,
    title: String,
    statement: String,
    hazards: Vec<String>,
    verified_by: Vec<String>,
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn read(path: &str) -> Result<String, String> {
    std::fs::read_to_string(root().join(path)).map_err(|e| format!("{path}: {e}"))
}

/// `line` without a leading visibility (`pub`, `pub(crate)`,
/// `pub(super)`, `pub(in …)`).
fn without_visibility(line: &str) -> &str {
    match line.strip_prefix("pub") {
        Some(rest) if rest.starts_with('(') => rest
            .split_once(')')
            .map_or(line, |(_, after)| after.trim_start()),
        Some(rest) if rest.starts_with(' ') => rest.trim_start(),
        _ => line,
    }
}

/// The doc comment and attribute lines directly above `fn name`.
fn doc_above(text: &str, name: &str) -> Option<String> {
    let lines: Vec<&str> = text.lines().collect();
    let at = lines
        .iter()
        .position(|l| without_visibility(l.trim_start()).starts_with(&format!("fn {name}(")))?;
    let mut doc = Vec::new();
    for line in lines[..at].iter().rev() {
        let t = line.trim_start();
        if t.starts_with("///") || t.starts_with("#[") || t.starts_with("//") {
            doc.push(t.to_string());
        } else {
            break;
        }
    }
    Some(doc.join("\n"))
}

/// Checks one `verified_by` entry of requirement `id`.
fn check_entry(id: &str, entry: &str) -> Result<(), String> {
    let (kind, rest) = entry
        .split_once(':')
        .ok_or(format!("{id}: malformed entry {entry}"))?;
    match kind {
        "test" | "proptest" | "kani" => {
            let (file, name) = rest
                .split_once("::")
                .ok_or(format!("{id}: malformed entry {entry}"))?;
            let text = read(file)?;
            let doc = doc_above(&text, name).ok_or(format!("{id}: {file} has no fn {name}"))?;
            if !doc.contains(id) {
                return Err(format!(
                    "{id}: {file}::{name} does not name {id} in its doc comment"
                ));
            }
            if kind == "kani"
                && !(name.starts_with("verify_req_")
                    && doc.contains("kani::proof")
                    && text.contains(&format!("fn {name}()")))
            {
                return Err(format!("{id}: {name} is not a verify_req_ Kani harness"));
            }
            if kind == "proptest" && !text.contains("proptest!") {
                return Err(format!("{id}: {file} has no proptest properties"));
            }
            Ok(())
        }
        "doctest" | "bench" | "ci" => {
            let (file, marker) = rest
                .split_once('#')
                .ok_or(format!("{id}: malformed entry {entry}"))?;
            let text = read(file)?;
            if !text.contains(marker) {
                return Err(format!("{id}: {file} does not contain {marker}"));
            }
            if kind == "doctest" && !text.contains("compile_fail") {
                return Err(format!("{id}: {file} has no compile_fail doc test"));
            }
            Ok(())
        }
        other => Err(format!("{id}: unknown kind {other}")),
    }
}

/// The `.rs` files under `dir` (relative to the root), recursively, sorted.
fn rust_files(dir: &str, out: &mut Vec<String>) {
    let mut entries: Vec<_> = std::fs::read_dir(root().join(dir))
        .map(|d| d.filter_map(Result::ok).map(|e| e.path()).collect())
        .unwrap_or_default();
    entries.sort();
    for path in entries {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if path.is_dir() {
            rust_files(&format!("{dir}/{name}"), out);
        } else if name.ends_with(".rs") {
            out.push(format!("{dir}/{name}"));
        }
    }
}

/// Every `req_*` test and `verify_req_*` harness in the repository's test
/// files and the kernel's sources, with the file it is in.
fn checks_in_repository() -> Vec<(String, String)> {
    let mut files = Vec::new();
    for dir in ["verification/tests", "kernel/tests", "kernel/src"] {
        rust_files(dir, &mut files);
    }
    let mut found = Vec::new();
    for file in files {
        let text = read(&file).unwrap();
        for line in text.lines() {
            let t = line.trim_start().trim_start_matches("pub ");
            if let Some(rest) = t.strip_prefix("fn ") {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if name.starts_with("req_") || name.starts_with("verify_req_") {
                    found.push((file.clone(), name));
                }
            }
        }
    }
    found
}

/// Which engines check a requirement: `kani` (harnesses written for real
/// Kani, sampled by the stand-in under `cargo test`), `proptest`, or both.
fn engines(r: &Requirement) -> &'static str {
    let has = |kind: &str| r.verified_by.iter().any(|v| v.starts_with(kind));
    match (has("kani:"), has("proptest:")) {
        (true, true) => "both",
        (true, false) => "kani",
        (false, true) => "proptest",
        (false, false) => "tests",
    }
}

fn table(spec: &Spec) -> String {
    let mut out = format!(
        "# Traceability\n\nGenerated by `verification/tests/traceability.rs` from \
         `requirements.toml` (run `LIMB_BLESS=1 cargo test -p limb-verification --test traceability` \
         to regenerate). Every requirement, the hazards it mitigates, the engines that check it \
         and the checks. Engines: `kani` = a Kani harness beside the code, written for `cargo kani` \
         under stated libm stubs (under `cargo test` only sampled by the stand-in), `proptest` = \
         a property over generated inputs, `both` = the two, `tests` = fixed cases and sessions \
         only (fixed-case tests may be cited beside any engine).\n\n\
         Real Kani {} with CBMC {} ({}; {}; `verification/kani-run.sh`): {} of {} harnesses \
         verified, each with every cover satisfied; each `kani:` check below says its result, \
         wall time and peak memory.\n\n\
         | requirement | title | hazards | engines | verified by |\n|---|---|---|---|---|\n",
        spec.kani.version,
        spec.kani.cbmc,
        spec.kani.date,
        spec.kani.machine,
        spec.kani.run.iter().filter(|r| r.result == "verified").count(),
        spec.kani.run.len(),
    );
    for r in &spec.requirement {
        let checks: Vec<String> = r
            .verified_by
            .iter()
            .map(|v| {
                let run = v
                    .strip_prefix("kani:")
                    .and_then(|rest| rest.split_once("::"))
                    .and_then(|(_, name)| spec.kani.run.iter().find(|run| run.harness == name));
                match run {
                    Some(run) => format!(
                        "`{v}` ({}, {} s, {} MiB, covers {}{})",
                        run.result,
                        run.seconds,
                        run.mib,
                        run.covers,
                        run.cbmc_args
                            .as_ref()
                            .map_or(String::new(), |args| format!(", CBMC `{args}`"))
                    ),
                    None => format!("`{v}`"),
                }
            })
            .collect();
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} |\n",
            r.id,
            r.title,
            r.hazards.join(", "),
            engines(r),
            checks.join("<br>")
        ));
    }
    out
}

#[test]
fn every_requirement_is_verified_and_every_check_traces_to_one() {
    let spec: Spec = toml::from_str(&read("spec/requirements.toml").unwrap()).unwrap();
    let hazards_text = read("spec/hazards.md").unwrap();
    let mut failures = Vec::new();
    let mut ids = BTreeSet::new();
    let mut referenced: BTreeMap<(String, String), Vec<String>> = BTreeMap::new();
    let mut hazards_covered = BTreeSet::new();
    for r in &spec.requirement {
        if !ids.insert(r.id.clone()) {
            failures.push(format!("{}: duplicate id", r.id));
        }
        if r.statement.trim().is_empty() || r.title.trim().is_empty() {
            failures.push(format!("{}: empty title or statement", r.id));
        }
        if r.verified_by.is_empty() {
            failures.push(format!("{}: no verification", r.id));
        }
        for entry in &r.verified_by {
            if let Err(e) = check_entry(&r.id, entry) {
                failures.push(e);
            }
            if let Some((file, name)) = entry
                .split_once(':')
                .and_then(|(_, rest)| rest.split_once("::"))
            {
                referenced
                    .entry((file.to_string(), name.to_string()))
                    .or_default()
                    .push(r.id.clone());
            }
        }
        for h in &r.hazards {
            if !hazards_text.contains(&format!("| {h} |")) {
                failures.push(format!("{}: unknown hazard {h}", r.id));
            }
            hazards_covered.insert(h.clone());
        }
    }
    for line in hazards_text.lines() {
        if let Some(h) = line.strip_prefix("| ").and_then(|l| l.split(' ').next()) {
            if h.starts_with("HAZ-") && !hazards_covered.contains(h) {
                failures.push(format!("{h}: no requirement mitigates it"));
            }
        }
    }
    for (file, name) in checks_in_repository() {
        let Some(cited_by) = referenced.get(&(file.clone(), name.clone())) else {
            failures.push(format!("{file}::{name}: named by no requirement"));
            continue;
        };
        let doc = doc_above(&read(&file).unwrap(), &name).unwrap_or_default();
        for token in doc.split(|c: char| !(c.is_alphanumeric() || c == '-')) {
            if token.starts_with("REQ-") && !ids.contains(token) {
                failures.push(format!("{file}::{name}: mentions unknown {token}"));
            }
        }
        if cited_by.is_empty() {
            failures.push(format!("{file}::{name}: no requirement"));
        }
    }
    let mut runs = BTreeMap::new();
    for run in &spec.kani.run {
        if !referenced.keys().any(|(_, name)| *name == run.harness) {
            failures.push(format!("kani.run: {} is not a cited harness", run.harness));
        }
        if !matches!(run.result.as_str(), "verified" | "timeout" | "failed") {
            failures.push(format!("kani.run: {}: result {}", run.harness, run.result));
        }
        if runs.insert(run.harness.as_str(), run).is_some() {
            failures.push(format!("kani.run: {} twice", run.harness));
        }
    }
    let cited_harnesses: BTreeSet<&str> = spec
        .requirement
        .iter()
        .flat_map(|r| &r.verified_by)
        .filter_map(|v| {
            v.strip_prefix("kani:")?
                .split_once("::")
                .map(|(_, name)| name)
        })
        .collect();
    for name in cited_harnesses {
        if !runs.contains_key(name) {
            failures.push(format!("kani.run: no run of {name}"));
        }
    }
    let generated = table(&spec);
    let path = root().join("spec/traceability.md");
    if std::env::var_os("LIMB_BLESS").is_some() {
        std::fs::write(&path, &generated).unwrap();
    } else if std::fs::read_to_string(&path).ok().as_deref() != Some(generated.as_str()) {
        failures.push("spec/traceability.md is stale: rerun with LIMB_BLESS=1".into());
    }
    assert!(
        failures.is_empty(),
        "traceability failures:\n{}",
        failures.join("\n")
    );
}
